#pragma once
// A data-assimilation problem: the forecast model over one interval, its additive noise Q (none
// for a deterministic model), and the linear observation y = H x + v, v ~ N(0, R), made after
// every `steps_per_observation`-th interval (1: after every one).
//
//   auto model = std::make_shared<implicit::da::Lorenz63Model>(Lorenz63{}, 0.01, 25);
//   implicit::da::Problem p{model, Eigen::MatrixXd::Identity(3, 3),   // H
//                           2.0 * Eigen::MatrixXd::Identity(3, 3),    // R
//                           {}};                                      // Q: deterministic
//   p.validate();   // throws InvalidArgument naming the matrix and what is wrong
//
// The filters keep one ForecastWorkspace per member, so a forecast allocates nothing.

#include <memory>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "implicit/da/lorenz.hpp"

namespace implicit::da {

/// Storage a model may use during a forecast (one per member, reused every cycle).
struct ForecastWorkspace {
  Lorenz96::Workspace l96;
};

/// The deterministic part of the dynamics, x <- M(x) over one observation interval.
class Model {
 public:
  virtual ~Model() = default;
  virtual int dim() const = 0;
  /// Advances x (of size dim()) by one observation interval.
  virtual void forecast(Eigen::VectorXd& x, ForecastWorkspace& w) const = 0;
  /// Advances x by one observation interval and sets `jacobian` (n x n) to dM/dx at the start
  /// (the implicit smoother's Gauss-Newton). The default throws InvalidArgument: a model
  /// without a derivative cannot be smoothed.
  virtual void forecast_jacobian(Eigen::VectorXd& x, Eigen::MatrixXd& jacobian,
                                 ForecastWorkspace& w) const;
  /// Sizes a workspace for this model.
  virtual void prepare(ForecastWorkspace& w) const { (void)w; }
  virtual std::string name() const = 0;
};

/// x <- A x (tests: with Gaussian noise the Kalman filter is exact).
class LinearModel final : public Model {
 public:
  explicit LinearModel(Eigen::MatrixXd a);
  int dim() const override { return static_cast<int>(a_.rows()); }
  void forecast(Eigen::VectorXd& x, ForecastWorkspace& w) const override;
  void forecast_jacobian(Eigen::VectorXd& x, Eigen::MatrixXd& jacobian,
                         ForecastWorkspace& w) const override;
  std::string name() const override { return "linear"; }
  const Eigen::MatrixXd& matrix() const { return a_; }

 private:
  Eigen::MatrixXd a_;
};

/// Lorenz-63, `substeps` RK4 steps of length dt per interval.
class Lorenz63Model final : public Model {
 public:
  Lorenz63Model(const Lorenz63& l, double dt, int substeps);
  int dim() const override { return 3; }
  void forecast(Eigen::VectorXd& x, ForecastWorkspace& w) const override;
  void forecast_jacobian(Eigen::VectorXd& x, Eigen::MatrixXd& jacobian,
                         ForecastWorkspace& w) const override;
  std::string name() const override { return "lorenz63"; }

 private:
  Lorenz63 l_;
  double dt_;
  int substeps_;
};

/// Lorenz-96, `substeps` RK4 steps of length dt per interval.
class Lorenz96Model final : public Model {
 public:
  Lorenz96Model(const Lorenz96& l, double dt, int substeps);
  int dim() const override { return l_.dim(); }
  void forecast(Eigen::VectorXd& x, ForecastWorkspace& w) const override;
  void forecast_jacobian(Eigen::VectorXd& x, Eigen::MatrixXd& jacobian,
                         ForecastWorkspace& w) const override;
  void prepare(ForecastWorkspace& w) const override { w.l96.resize(l_.dim()); }
  std::string name() const override { return "lorenz96"; }

 private:
  Lorenz96 l_;
  double dt_;
  int substeps_;
};

/// The model and the Gaussian noises of one assimilation problem.
struct Problem {
  std::shared_ptr<const Model> model;
  Eigen::MatrixXd H;  ///< observation operator, p x n
  Eigen::MatrixXd R;  ///< observation noise covariance, p x p, SPD
  Eigen::MatrixXd Q;  ///< model noise covariance, n x n SPD, or empty: deterministic model
  /// K: intervals (each followed by its own noise Q) from one observation to the next. With K > 1
  /// and model noise, the state at an observation is a nonlinear function of K noises, so the
  /// optimal proposal has no closed form (path_objective.hpp samples the K noises implicitly).
  int steps_per_observation = 1;

  int dim() const { return model ? model->dim() : 0; }
  int obs_dim() const { return static_cast<int>(H.rows()); }
  bool stochastic() const { return Q.size() > 0; }
  /// Throws InvalidArgument for a missing model, H of the wrong width, R or Q of the wrong size,
  /// not finite, not symmetric or not positive definite, or steps_per_observation < 1.
  void validate() const;
};

/// Throws InvalidArgument unless `m` is a finite, symmetric, positive-definite `size` x `size`
/// matrix; `what` names it in the message ("observation noise R").
void require_spd(const Eigen::MatrixXd& m, int size, const char* what);

/// Throws InvalidArgument unless y has the problem's observation size and is finite; `cycle`
/// names the observation in the message.
void require_observation(const Problem& p, const Eigen::VectorXd& y, long cycle);

}  // namespace implicit::da
