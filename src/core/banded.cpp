// Explicit instantiations of the block-tridiagonal types for the block sizes used by the
// library (scalar paths and planar paths), so that users of these sizes do not recompile them.
#include "implicit/core/block_tridiagonal.hpp"

namespace implicit {
template struct BlockTridiagonal<1>;
template struct BlockTridiagonal<2>;
template class BlockTridiagonalCholesky<1>;
template class BlockTridiagonalCholesky<2>;
}  // namespace implicit
