#pragma once
// The motion models the tools know by name: one registry from which `--model`'s choices and
// help (mcl, slam, simulate), the check of a log's `vehicle` record, Python's `model=` and the
// table of docs/formats.md are drawn. A new robot is one file with its model (the
// robot::LinearizableMotionModel concept) and one registration, in C++ or from Python:
//
//   experiments::MotionModelEntry e;
//   e.name = "toy";
//   e.controls = "u1 = v [m/s], u2 = omega [rad/s]";
//   e.keys = {{"dt", "control period [s]", 0.1}};
//   e.default_noise = {{0.1, 0.05}, {0.02, 0.02, 0.0035}};
//   e.build = [](const robot::VehicleDeclaration& v, const experiments::MotionNoise& noise) {
//     return robot::AnyMotionModel(ToyModel(*v.parameter("dt"), noise));
//   };
//   const experiments::MotionModelRegistration toy{e};   // at namespace scope, in a .cpp
//
// and `implicit mcl --model toy`, `implicit simulate --model toy` run it (docs/design.md, "A new
// motion model"). The built-in models come first, in a fixed order; later registrations follow
// in the order they were made. The estimators run the built-ins through their own C++ types
// (visit_motion_model), every other model through robot::AnyMotionModel.

#include <deque>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "experiments/vehicle.hpp"
#include "implicit/robot/any_motion_model.hpp"
#include "implicit/robot/log_format.hpp"
#include "implicit/robot/simulate.hpp"
#include "implicit/robot/unicycle_model.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::experiments {

/// One key of a model's `vehicle` record, with the value a log that omits it gets.
struct VehicleKey {
  std::string name;
  std::string meaning;  ///< with its unit
  double default_value = 0.0;
};

/// What the tools need to run a motion model they know by name.
struct MotionModelEntry {
  std::string name;              ///< --model and the `vehicle` record's model, e.g. "unicycle"
  std::string description;       ///< one line for --help and docs/formats.md
  std::string controls;          ///< what u1 and u2 are, with units
  std::vector<VehicleKey> keys;  ///< the `vehicle` record's keys, dt first
  /// The model from a declaration with every key (an unknown key is an InvalidArgument naming
  /// the keys the model has) and the noise (both vectors given). Called through
  /// make_motion_model, which completes both first.
  std::function<robot::AnyMotionModel(const robot::VehicleDeclaration&, const MotionNoise&)> build;
  /// The default noise: sd of u1, u2 and of x, y, heading per sqrt(s).
  MotionNoise default_noise;
  /// `implicit simulate`: the controls that follow a square route at `speed` (default
  /// route_speed). Empty: the unicycle's driver (v, omega), which suits any model whose controls
  /// are a speed and a turn rate.
  std::function<robot::Driver(double speed, double side)> route_driver;
  double route_speed = 1.0;  ///< [m/s]
  /// The Car Park's noise settings apply (mcl --config, --p, --q; slam --control-noise): they
  /// set the Ute's P and Q, so only a model with the Ute's controls takes them.
  bool car_park_noise = false;
};

/// Every model the tools know: the built-ins ("ute", "unicycle"), then the registered ones. A
/// deque, so that a registration leaves the entries already handed out where they are; register
/// before running, not while another thread runs.
const std::deque<MotionModelEntry>& motion_models();
/// The names, in that order.
std::vector<std::string> motion_model_names();
/// The entry named `name`; an InvalidArgument naming `what` (e.g. "mcl --model") and the
/// names known otherwise.
const MotionModelEntry& motion_model(std::string_view name, std::string_view what);
/// For messages: the names as "'ute', 'unicycle', 'toy'".
std::string motion_model_quoted_names();
/// For --help: the names as "ute, unicycle or toy".
std::string motion_model_choices();
/// For --control-sd's help: what u1 and u2 are per model, with the default sd.
std::string motion_noise_help();
/// Adds a model. An empty name, a name already known, no build function or no dt key is an
/// InvalidArgument.
void register_motion_model(MotionModelEntry entry);

/// Registers at static initialisation (one object per model file). Only a file linked into the
/// program directly registers this way: a static library drops an object nothing refers to.
struct MotionModelRegistration {
  explicit MotionModelRegistration(MotionModelEntry entry) {
    register_motion_model(std::move(entry));
  }
};

/// The declaration a log that declares none runs with, and the one `simulate` writes: `name`
/// with every key at its default, then the given declaration's values.
robot::VehicleDeclaration full_declaration(const MotionModelEntry& entry,
                                           const robot::VehicleDeclaration& declared);

/// The noise flags with the model's defaults where a vector is empty; a vector of the wrong size
/// (2 for u1 u2, 3 for x y heading) is an InvalidArgument naming its flag.
MotionNoise noise_with_defaults(const MotionModelEntry& entry, const MotionNoise& flags);

/// The model `entry` builds from `declared` (completed by full_declaration) and the noise flags
/// (an empty vector: the model's default; else 2 values for u1 u2 and 3 for x y heading).
robot::AnyMotionModel make_motion_model(const MotionModelEntry& entry,
                                        const robot::VehicleDeclaration& declared,
                                        const MotionNoise& flags);

/// Calls f with the model as its own C++ type when it is a built-in (the estimators' fast path:
/// no indirect call per particle), else with the AnyMotionModel itself.
template <typename F>
decltype(auto) visit_motion_model(const robot::AnyMotionModel& model, F&& f) {
  if (const auto* ute = model.target<robot::UteModel>()) return f(*ute);
  if (const auto* unicycle = model.target<robot::UnicycleModel>()) return f(*unicycle);
  return f(model);
}

}  // namespace implicit::experiments
