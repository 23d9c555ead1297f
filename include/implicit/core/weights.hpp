#pragma once
// Importance weights in the log domain: log-sum-exp, normalisation, ESS, weighted moments.
//
// Always carry log w. Normalise with the maximum subtracted (log-sum-exp), so weights like
// exp(-1000) are fine. If every weight is zero (all log w = -inf, e.g. every particle outside the
// support) normalize_log_weights reports `all_zero` and returns uniform weights: a documented
// recovery that callers (filters) may log or act on. NaN log-weights are a bug upstream and throw.

#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "implicit/core/error.hpp"
#include "implicit/core/types.hpp"

namespace implicit {

/// log(sum_i exp(a_i)); -inf for an empty span or all -inf entries.
double log_sum_exp(std::span<const double> a);

/// log((1/n) sum_i exp(a_i)): the log of the mean weight, e.g. log Z-hat.
double log_mean_exp(std::span<const double> a);

struct WeightSummary {
  double log_mean = -std::numeric_limits<double>::infinity();  ///< log of the mean raw weight
  double ess = 0.0;       ///< effective sample size 1 / sum w_bar^2
  bool all_zero = false;  ///< every log-weight was -inf; uniform weights were returned
};

/// Writes normalised weights w_bar (summing to 1) into `normalized`. Throws InvalidArgument for
/// NaN or +inf log-weights (naming the first index) or mismatched sizes.
WeightSummary normalize_log_weights(std::span<const double> log_weights,
                                    std::span<double> normalized);

/// Effective sample size of normalised weights: 1 / sum w_i^2.
double effective_sample_size(std::span<const double> normalized);

/// Standard error of the mean of raw weights exp(l_i) relative to that mean: sd(w)/(sqrt(M) mean).
double relative_standard_error(std::span<const double> log_weights);

/// log_mean_exp, the ESS (sum w)^2 / sum w^2 and relative_standard_error of raw log-weights in one
/// pass of exponentials (the other functions take one each: this is for hot loops). All -inf (or
/// empty): log_mean = -inf, ess = 0, relative_se = +inf.
struct WeightMoments {
  double log_mean = -std::numeric_limits<double>::infinity();
  double ess = 0.0;
  double relative_se = std::numeric_limits<double>::infinity();
};
WeightMoments weight_moments(std::span<const double> log_weights);

/// Weighted mean of the columns of `samples` (each column one sample).
template <int N>
Vec<N> weighted_mean(const Eigen::Matrix<double, N, Eigen::Dynamic>& samples,
                     std::span<const double> w) {
  require(static_cast<std::size_t>(samples.cols()) == w.size(),
          "weighted_mean: expected {} weights, got {}", samples.cols(), w.size());
  Vec<N> m = Vec<N>::Zero(samples.rows());
  for (std::size_t j = 0; j < w.size(); ++j) m += w[j] * samples.col(static_cast<Eigen::Index>(j));
  return m;
}

/// Weighted covariance sum_j w_j (x_j - m)(x_j - m)^T of the columns, about the weighted mean.
template <int N>
Mat<N> weighted_covariance(const Eigen::Matrix<double, N, Eigen::Dynamic>& samples,
                           std::span<const double> w) {
  const Vec<N> m = weighted_mean<N>(samples, w);
  Mat<N> c = Mat<N>::Zero(samples.rows(), samples.rows());
  for (std::size_t j = 0; j < w.size(); ++j) {
    const Vec<N> d = samples.col(static_cast<Eigen::Index>(j)) - m;
    c += w[j] * d * d.transpose();
  }
  return c;
}

/// Circular mean atan2(sum w sin a, sum w cos a) of angles (never average raw angles).
double circular_mean(std::span<const double> angles, std::span<const double> w);

/// Wraps an angle to [-pi, pi).
inline double wrap_angle(double a) { return a - 2.0 * kPi * std::floor((a + kPi) / (2.0 * kPi)); }

}  // namespace implicit
