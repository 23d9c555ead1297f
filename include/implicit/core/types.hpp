#pragma once
// Small vocabulary types shared by every layer: fixed- or dynamic-size Eigen vectors and matrices.

#include <limits>

#include <Eigen/Core>

namespace implicit {

/// Column vector of dimension N (Eigen::Dynamic for run-time sizes).
template <int N>
using Vec = Eigen::Matrix<double, N, 1>;

/// Square matrix N x N (Eigen::Dynamic for run-time sizes).
template <int N>
using Mat = Eigen::Matrix<double, N, N>;

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kLog2Pi = 1.83787706640934548356;  // log(2 pi)
inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// How implicit sampling maps a reference sample xi to a sample (spec §1.2, §1.3). One choice for
/// every layer: the sampler's, the filters' proposals and path integral control's.
enum class MapKind {
  kLinear,  ///< x = mu + L^-T xi, weight exp(F_hat - F)
  kRandom,  ///< x = mu + lambda L^-T xi / |xi| with F(x) - phi = |xi|^2 / 2
};

}  // namespace implicit
