#include "implicit/core/version.hpp"

#include "implicit/build_info.hpp"

namespace implicit {
const char* version() { return build_info::version; }
const char* git_commit() { return build_info::commit; }
}  // namespace implicit
