#pragma once
// The paper's double slit (double_slit.hpp, spec §2.4) as a generic path integral control
// problem (problem.hpp): dx = u dt + sqrt(sigma) dW is dx = G (u dt + Q dW) with G = 1 and
// Q Q^T = sigma, the cost r u^2 / 2 gives R = r (so condition (8) yields gamma = r sigma, spec
// E10), the end cost is Phi = x(tf)^2 / 2 without a running cost (FreeWalkerModel), and the
// wall at t1 is a HardWall whose openings are the two slits. The generic estimators
// (estimators.hpp, controller.hpp) then estimate the log psi and the control whose exact values
// DoubleSlit::exact_log_psi and DoubleSlit::exact_control give:
//
//   const auto problem = implicit::control::double_slit_problem();   // Table 1 parameters
//   auto c = estimate_control(problem, implicit::Vec<1>(1.0), 0, {.samples = 50}, {.seed = 1});
//
// Grid step k is the time t = k dt, as in DoubleSlit. With PathGrid::kWallsAndHorizon the path is
// resolved at t1 and tf only, which is exact for this model and much faster. The slits are closed
// intervals and the openings open ones: the edges have probability zero, so psi is the same.

#include "implicit/control/double_slit.hpp"
#include "implicit/control/problem.hpp"

namespace implicit::control {

using DoubleSlitProblem = ControlProblem<1, 1, FreeWalkerModel>;

/// G = 1, Q Q^T = sigma, R = r, horizon tf, step dt, the path resolved where `grid` says.
ControlSpec<1, 1> double_slit_spec(const DoubleSlitParameters& p,
                                   PathGrid grid = PathGrid::kEveryStep);

/// The wall at t1 along x with the openings (lower, upper) of the two slits.
HardWall<1> double_slit_wall(const DoubleSlitParameters& p);

/// The double slit as a generic problem with the wall. PathGrid::kWallsAndHorizon is exact here
/// (no drift, no running cost) and samples 2-D paths (the wall and tf) instead of K - k steps.
/// Throws InvalidArgument for bad parameters (check_double_slit_parameters).
DoubleSlitProblem double_slit_problem(const DoubleSlitParameters& p = {},
                                      PathGrid grid = PathGrid::kEveryStep);

}  // namespace implicit::control
