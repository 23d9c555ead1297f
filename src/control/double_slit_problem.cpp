#include "implicit/control/double_slit_problem.hpp"

namespace implicit::control {

ControlSpec<1, 1> double_slit_spec(const DoubleSlitParameters& p, PathGrid grid) {
  ControlSpec<1, 1> s;
  s.path_grid = grid;
  s.G << 1.0;
  s.noise_covariance << p.sigma;
  s.control_cost << p.control_cost;
  s.horizon = p.final_time;
  s.dt = p.dt;
  return s;
}

HardWall<1> double_slit_wall(const DoubleSlitParameters& p) {
  HardWall<1> wall;
  wall.time = p.wall_time;
  for (const Slit& s : p.slits) wall.openings.push_back({s.lower, s.upper});
  return wall;
}

DoubleSlitProblem double_slit_problem(const DoubleSlitParameters& p, PathGrid grid) {
  check_double_slit_parameters(p);
  return DoubleSlitProblem(FreeWalkerModel{}, double_slit_spec(p, grid), {double_slit_wall(p)});
}

}  // namespace implicit::control
