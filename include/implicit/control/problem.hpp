#pragma once
// The generic path integral control problem: the linear parts (G, Q Q^T, R, horizon, dt) with
// condition (8), hard walls, and ControlProblem, which binds a user's model to them. See
// path_integral.hpp for the whole picture and an example. With partial noise (the last Dv < D
// coordinates noisy, e.g. velocities driven by forces) the path integral runs over the noisy
// coordinates only (partial_noise.hpp).

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "implicit/control/partial_noise.hpp"
#include "implicit/control/path_function.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/gaussian.hpp"
#include "implicit/core/types.hpp"

namespace implicit::control {

/// The linear parts of a control problem: D states, P controls.
template <int D, int P>
struct ControlSpec {
  Eigen::Matrix<double, D, P> G = Eigen::Matrix<double, D, P>::Zero();  ///< input matrix
  Mat<P> noise_covariance = Mat<P>::Identity();  ///< Q Q^T (the noise enters as G Q dW)
  Mat<P> control_cost = Mat<P>::Identity();      ///< R (symmetric positive definite)
  double horizon = 1.0;                          ///< tf - t0
  double dt = 0.01;                              ///< time step; horizon must be a multiple
  PathGrid path_grid = PathGrid::kEveryStep;     ///< where the path integral resolves the path
};

/// Checks the spec and condition (8); returns gamma and writes Sigma = G Q Q^T G^T. Throws
/// InvalidArgument naming the problem (dt, horizon, R, Q Q^T, the mismatching entry of (8), or a
/// singular Sigma). With `noise_free` > 0 the first `noise_free` rows of G must be zero and Sigma
/// is checked on the remaining (noisy) coordinates only.
template <int D, int P>
double check_control_spec(const ControlSpec<D, P>& s, Mat<D>* sigma_out = nullptr,
                          int noise_free = 0) {
  require(std::isfinite(s.dt) && s.dt > 0.0, "control problem: expected dt > 0, got {}", s.dt);
  const double steps = s.horizon / s.dt;
  require(
      std::isfinite(steps) && steps >= 1.0 && std::abs(steps - std::round(steps)) <= 1e-9 * steps,
      "control problem: expected the horizon to be a positive multiple of dt, got {} / {} = {}",
      s.horizon, s.dt, steps);
  require(s.G.allFinite() && s.noise_covariance.allFinite() && s.control_cost.allFinite(),
          "control problem: expected finite G, Q Q^T and R");
  const Mat<P>& R = s.control_cost;
  require((R - R.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * (1.0 + R.cwiseAbs().maxCoeff()),
          "control problem: expected a symmetric control cost R");
  const Eigen::LLT<Mat<P>> r_llt(R);
  require(r_llt.info() == Eigen::Success,
          "control problem: expected a positive definite control cost R, but its Cholesky "
          "factorisation failed");
  const Mat<P>& N = s.noise_covariance;
  require((N - N.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * (1.0 + N.cwiseAbs().maxCoeff()),
          "control problem: expected a symmetric noise covariance Q Q^T");
  const Eigen::SelfAdjointEigenSolver<Mat<P>> eig(N);
  const double min_eig = eig.eigenvalues().minCoeff();
  require(min_eig >= -1e-12 * (1.0 + eig.eigenvalues().cwiseAbs().maxCoeff()),
          "control problem: expected a positive semi-definite noise covariance Q Q^T, got the "
          "eigenvalue {}",
          min_eig);
  const Mat<D> A = s.G * r_llt.solve(s.G.transpose());  // G R^-1 G^T
  const Mat<D> B = s.G * N * s.G.transpose();           // G Q Q^T G^T
  require(A.trace() > 0.0, "control problem: expected a non-zero input matrix G");
  const double gamma = B.trace() / A.trace();
  require(gamma > 0.0, "control problem: expected noise acting through G, got G Q Q^T G^T = 0");
  const Mat<D> mismatch = gamma * A - B;
  Eigen::Index i = 0, j = 0;
  const double worst = mismatch.cwiseAbs().maxCoeff(&i, &j);
  require(worst <= 1e-9 * (1.0 + B.cwiseAbs().maxCoeff()),
          "control problem: condition (8) gamma G R^-1 G^T = G Q Q^T G^T has no solution: with the "
          "best gamma = {}, entry ({}, {}) is {} on the left and {} on the right (choose R "
          "proportional to (Q Q^T)^-1 on the controlled subspace)",
          gamma, i, j, gamma * A(i, j), B(i, j));
  if (noise_free > 0) {
    const double g_top = s.G.topRows(noise_free).cwiseAbs().maxCoeff();
    require(g_top == 0.0,
            "control problem: with partial noise the first {} (noise-free) rows of G must be zero, "
            "but an entry is {}",
            noise_free, g_top);
  }
  const int noisy = D - noise_free;
  // The noise-free rows and columns of Sigma are zero (G's are): an identity there leaves a
  // matrix that is SPD exactly when Sigma is on the noisy coordinates.
  Mat<D> padded = B;
  padded.topLeftCorner(noise_free, noise_free).setIdentity();
  const Eigen::LLT<Mat<D>> s_llt(padded);
  require(s_llt.info() == Eigen::Success || noise_free == 0,
          "control problem: the noise covariance Sigma = G Q Q^T G^T is singular on the noisy "
          "coordinates (the last {} of the state)",
          noisy);
  require(s_llt.info() == Eigen::Success,
          "control problem: the noise covariance Sigma = G Q Q^T G^T is singular (noise acts on a "
          "subspace only); order the state with the noise-free coordinates first and declare the "
          "number Dv of noisy ones, ControlProblem<D, P, Model, Dv> (partial_noise.hpp)");
  if (sigma_out) *sigma_out = B;
  return gamma;
}

/// An opening (lower, upper) of a hard wall; either end may be infinite.
struct WallOpening {
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  bool contains(double v) const { return v > lower && v < upper; }
};

/// A hard wall: at the grid time `time` the path must have direction^T x(time) inside one of the
/// `openings` (sorted, disjoint); elsewhere V = +inf. Several walls may be given.
template <int D>
struct HardWall {
  double time = 0.0;                   ///< a grid time in (0, horizon]
  Vec<D> direction = Vec<D>::Unit(0);  ///< a: the wall tests a^T x (default: coordinate 0)
  std::vector<WallOpening> openings;   ///< where a^T x may pass
  bool passes(const Vec<D>& x) const {
    const double v = direction.dot(x);
    for (const auto& o : openings)
      if (o.contains(v)) return true;
    return false;
  }
};

/// Dv: the number of noisy coordinates, the last Dv of the state (D: all of them). With Dv < D
/// the first D - Dv rows of G must be zero, the path integral runs over the noisy coordinates
/// (partial_noise.hpp) and hard walls and PathGrid::kWallsAndHorizon are not available.
template <int D, int P, typename Model, int Dv = D>
class ControlProblem {
  static_assert(Dv >= 1 && Dv <= D, "ControlProblem: expected 1 <= Dv <= D noisy coordinates");
  // F is a class of its own (path_function.hpp, partial_noise.hpp); it reads the model and
  // Sigma^-1 directly.
  friend class control::PathFunction<D, ControlProblem>;
  friend class control::PartialNoisePathFunction<D, Dv, ControlProblem>;

 public:
  using PathFunction = std::conditional_t<Dv == D, control::PathFunction<D, ControlProblem>,
                                          control::PartialNoisePathFunction<D, Dv, ControlProblem>>;
  using ModelType = Model;
  static constexpr int kStateDim = D;
  static constexpr int kControlDim = P;
  static constexpr int kNoisyDim = Dv;  ///< path entries per resolved time

  /// Throws InvalidArgument for a bad spec (see check_control_spec) or a bad wall (time not a
  /// grid time in (0, horizon], zero or non-finite direction, no openings, openings empty,
  /// unsorted or overlapping).
  ControlProblem(Model model, const ControlSpec<D, P>& spec, std::vector<HardWall<D>> walls = {})
      : model_(std::move(model)), spec_(spec), walls_(std::move(walls)) {
    gamma_ = check_control_spec(spec_, &sigma_, D - Dv);
    const Mat<Dv> noisy = sigma_.template bottomRightCorner<Dv, Dv>();
    Eigen::LLT<Mat<Dv>> noisy_llt;
    noisy_llt.compute(noisy);
    noise_inv_ = noisy_llt.solve(Mat<Dv>::Identity());
    const Mat<Dv> root = noisy_llt.matrixL();
    sigma_sqrt_.setZero();  // zero rows and columns for the noise-free coordinates
    sigma_sqrt_.template bottomRightCorner<Dv, Dv>() = root;
    if constexpr (Dv == D) sigma_inv_ = noise_inv_;
    log_det_sigma_ = 2.0 * root.diagonal().array().log().sum();
    num_steps_ = static_cast<int>(std::round(spec_.horizon / spec_.dt));
    if constexpr (Dv < D) {
      require(walls_.empty(),
              "control problem: hard walls need noise on every coordinate (Dv = D), got {} walls "
              "with {} of {} coordinates noisy",
              walls_.size(), Dv, D);
      require(spec_.path_grid == PathGrid::kEveryStep,
              "control problem: with partial noise the path must be resolved at every step "
              "(PathGrid::kEveryStep): the noise-free coordinates integrate the noisy ones");
    }
    for (std::size_t j = 0; j < walls_.size(); ++j) {
      const auto& w = walls_[j];
      const double r = w.time / spec_.dt, step = std::round(r);
      require(std::isfinite(r) && std::abs(r - step) <= 1e-9 * std::max(1.0, r) && step >= 1.0 &&
                  step <= num_steps_,
              "hard wall {}: expected a time that is a multiple of dt = {} in (0, {}], got {}", j,
              spec_.dt, spec_.horizon, w.time);
      require(w.direction.allFinite() && w.direction.norm() > 0.0,
              "hard wall {}: expected a finite non-zero direction", j);
      require(!w.openings.empty(), "hard wall {}: expected at least one opening, got none", j);
      for (std::size_t o = 0; o < w.openings.size(); ++o) {
        const auto& op = w.openings[o];
        require(!std::isnan(op.lower) && !std::isnan(op.upper) && op.lower < op.upper,
                "hard wall {}, opening {}: expected lower < upper, got ({}, {})", j, o, op.lower,
                op.upper);
        if (o == 0) continue;  // the message's arguments read opening o - 1: only past the first
        require(w.openings[o - 1].upper <= op.lower,
                "hard wall {}, opening {}: expected sorted disjoint openings, got ({}, {}) after "
                "({}, {})",
                j, o, op.lower, op.upper, w.openings[o - 1].lower, w.openings[o - 1].upper);
      }
      wall_steps_.push_back(static_cast<int>(step));
    }
    if (spec_.path_grid == PathGrid::kEveryStep) {
      for (int i = 1; i <= num_steps_; ++i) nodes_.push_back(i);
    } else {
      nodes_ = wall_steps_;
      nodes_.push_back(num_steps_);
      std::sort(nodes_.begin(), nodes_.end());
      nodes_.erase(std::unique(nodes_.begin(), nodes_.end()), nodes_.end());
    }
  }

  const Model& model() const { return model_; }
  const ControlSpec<D, P>& spec() const { return spec_; }
  double gamma() const { return gamma_; }
  const Mat<D>& sigma() const { return sigma_; }
  double dt() const { return spec_.dt; }
  int num_steps() const { return num_steps_; }
  double time(int k) const { return k * spec_.dt; }
  const std::vector<HardWall<D>>& walls() const { return walls_; }
  /// The grid step of wall j.
  int wall_step(std::size_t j) const { return wall_steps_[j]; }

  /// n: the number of resolved path points y_1..y_n after grid step k (K - k on every step).
  int path_length(int k) const { return static_cast<int>(nodes_.end() - first_node(k)); }
  /// The grid steps of y_1..y_n from step k (path_length(k) entries, increasing, the last is K).
  const int* path_steps(int k) const { return nodes_.data() + (first_node(k) - nodes_.begin()); }
  /// The 0-based block of the path from step k that holds the resolved grid step `step` > k.
  int block_at_step(int k, int step) const {
    const auto it = std::lower_bound(first_node(k), nodes_.end(), step);
    return static_cast<int>(it - first_node(k));
  }

  /// True if the path y_1..y_n from (x, t_k) passes every wall at or after t_k (walls at t_k test
  /// x itself unless `test_start` is false; earlier walls are behind and ignored).
  bool passes_walls(const Vec<D>& x, int k, const Eigen::VectorXd& y,
                    bool test_start = true) const {
    for (std::size_t j = 0; j < walls_.size(); ++j) {
      const int w = wall_steps_[j] - k;
      if (w < 0 || (w == 0 && !test_start)) continue;
      const Vec<D> at =
          w == 0 ? x : Vec<D>(y.template segment<D>(block_at_step(k, wall_steps_[j]) * D));
      if (!walls_[j].passes(at)) return false;
    }
    return true;
  }

  /// u = gamma R^-1 G^T grad log psi.
  Vec<P> control_from_gradient(const Vec<D>& grad_log_psi) const {
    return control_from_slopes(spec_.G.transpose() * grad_log_psi);
  }
  /// u = gamma R^-1 s from the slopes s_j = g_j^T grad log psi along the columns of G.
  Vec<P> control_from_slopes(const Vec<P>& slopes) const {
    const Eigen::LLT<Mat<P>> llt(spec_.control_cost);
    return gamma_ * llt.solve(slopes);
  }

  /// F over y_1..y_n (n = path_length(k)) from y_0 = x at t_k: a banded target with D x D blocks
  /// (PathFunction), or with partial noise a dense one over the noisy coordinates
  /// (PartialNoisePathFunction).
  PathFunction path_function(const Vec<D>& x, int k) const {
    require(k >= 0 && k < num_steps_, "control problem: expected a step in [0, {}), got {}",
            num_steps_, k);
    require(x.allFinite(), "control problem: expected a finite state");
    return PathFunction(this, x, k);
  }

  /// The noise-free forward-Euler path from (x, t_k): a start point for the minimiser (its
  /// noisy coordinates only with partial noise).
  Eigen::VectorXd drift_path(const Vec<D>& x, int k) const {
    const int n = path_length(k);
    const int* steps = path_steps(k);
    Eigen::VectorXd y(n * Dv);
    Vec<D> cur = x;
    for (int i = 1, from = k; i <= n; from = steps[i - 1], ++i) {
      cur = cur + model_.drift(cur, time(from)) * ((steps[i - 1] - from) * spec_.dt);
      y.template segment<Dv>((i - 1) * Dv) = cur.template tail<Dv>();
    }
    return y;
  }

  /// log of the path-integral normaliser prod_i (2 pi dt_i)^{Dv/2} (det Sigma)^{1/2} over the
  /// path from step k, dt_i the interval before y_i (dt on every step); Sigma on the noisy
  /// coordinates.
  double path_log_normalizer(int k) const {
    const int n = path_length(k);
    if (spec_.path_grid == PathGrid::kEveryStep)
      return gaussian_log_normaliser(n * Dv, 0.5 * n * (Dv * std::log(spec_.dt) + log_det_sigma_));
    double s = 0.5 * n * log_det_sigma_;
    const int* steps = path_steps(k);
    for (int i = 0, from = k; i < n; from = steps[i], ++i)
      s += gaussian_log_normaliser(Dv, 0.5 * Dv * std::log((steps[i] - from) * spec_.dt));
    return s;
  }

  /// Lower Cholesky factor of Sigma (forward-Euler increments are sqrt(dt) Sigma^{1/2} w); zero
  /// on the noise-free coordinates.
  const Mat<D>& sigma_sqrt() const { return sigma_sqrt_; }

 private:
  Model model_;
  ControlSpec<D, P> spec_;
  std::vector<HardWall<D>> walls_;
  std::vector<int> wall_steps_;
  std::vector<int> nodes_;  // the resolved grid steps 1..K (path_grid), increasing
  double gamma_ = 0.0;
  Mat<D> sigma_, sigma_inv_ = Mat<D>::Zero(), sigma_sqrt_;
  Mat<Dv> noise_inv_;  // Sigma^-1 on the noisy coordinates
  double log_det_sigma_ = 0.0;
  int num_steps_ = 0;

  std::vector<int>::const_iterator first_node(int k) const {
    return std::upper_bound(nodes_.begin(), nodes_.end(), k);
  }
};

}  // namespace implicit::control
