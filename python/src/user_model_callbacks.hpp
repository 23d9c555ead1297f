#pragma once
// The Python callbacks of a user's state-space model (implicit.ssm.Model) and F built from them.
// Every callback works on k points at once (arrays of shape (k, d)); k is the number of
// particles, a subset of them (Newton's unfinished particles) or the stacked points of a finite
// difference. What a callback returns is checked here: a wrong shape, NaN or +inf raises
// InvalidArgument naming the callback and the step; -inf log densities mean density zero.

#include <string>
#include <utility>
#include <vector>

#include "common.hpp"
#include "user_model.hpp"

namespace implicit::python::ssm {

py::array_t<double> to_numpy(const RowMatrix& m);

/// The model's callbacks at one step (`step`, observation `y`); unset ones are None.
struct Callbacks {
  Eigen::Index dim = 1;
  py::object initial, transition, transition_logpdf, observation_logpdf, gradient, hessian,
      proposal;
  long long step = 0;
  py::object y;

  std::string where(const char* name) const;  ///< "name at step t", for messages
  RowMatrix sample_initial(const RowMatrix& z) const;
  RowMatrix sample_transition(const RowMatrix& x_prev, const RowMatrix& z) const;
  VecX observation(const RowMatrix& x) const;                                  ///< log p(y | x)
  VecX transition_density(const RowMatrix& x, const RowMatrix& x_prev) const;  ///< log p(x | x')
  /// The user's proposal: samples and their log proposal densities.
  std::pair<RowMatrix, VecX> guided(const RowMatrix& x_prev, const RowMatrix& z) const;
  /// F = -log p(y | x) - log p(x | x'), +inf where a density is zero.
  VecX objective(const RowMatrix& x, const RowMatrix& x_prev) const;

 private:
  RowMatrix points(const py::object& result, const char* name, Eigen::Index k) const;
  VecX log_densities(const py::object& result, const char* name, Eigen::Index k,
                     bool allow_minus_inf) const;
};

/// F for the lockstep Newton: the callbacks at one step, the particles' previous states.
class PythonObjective : public BatchObjective {
 public:
  PythonObjective(const Callbacks& callbacks, const RowMatrix& previous)
      : cb(callbacks), x_prev(previous) {}
  void evaluate(const std::vector<std::size_t>& owner, const RowMatrix& x, Derivatives derivatives,
                Evaluation& out) override;
  int calls = 0;  ///< batched evaluations (Python calls of F, each with its derivatives)

 private:
  RowMatrix user_gradient(const RowMatrix& x, const RowMatrix& xp, const VecX& value) const;
  void user_hessian(const RowMatrix& x, const RowMatrix& xp, Evaluation& out) const;
  void gradient_differenced(const RowMatrix& x, const RowMatrix& xp, Evaluation& out) const;
  void values_differenced(const RowMatrix& x, const RowMatrix& xp, Evaluation& out,
                          bool hessian) const;

  const Callbacks& cb;
  const RowMatrix& x_prev;
};

}  // namespace implicit::python::ssm
