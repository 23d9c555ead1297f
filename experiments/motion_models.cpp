#include "experiments/motion_models.hpp"

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit::experiments {
namespace {

robot::RobotLog declaring(const robot::VehicleDeclaration& v) {
  robot::RobotLog log;
  log.vehicle = v;
  return log;
}

std::vector<double> as_vector(const Vec<2>& v) { return {v(0), v(1)}; }
std::vector<double> as_vector(const Vec<3>& v) { return {v(0), v(1), v(2)}; }

MotionModelEntry ute_entry() {
  const robot::UteParams d;
  MotionModelEntry e;
  e.name = "ute";
  e.description =
      "the Car Park's car (the paper's Ute): steered front wheels, encoder on the "
      "rear left, laser ahead of the rear axle";
  e.controls = "u1 = axle speed [m/s], u2 = steering angle [rad]";
  e.keys = {{"dt", "control period [s]", d.dt},
            {"L", "wheelbase [m]", d.wheelbase},
            {"H", "rear-left encoder to the axle's centre [m]", d.encoder_offset},
            {"a", "laser ahead of the rear axle [m]", d.laser_forward},
            {"b", "laser to the left [m]", d.laser_left}};
  e.build = [](const robot::VehicleDeclaration& v, const MotionNoise& noise) {
    return robot::AnyMotionModel(robot::UteModel(ute_params(declaring(v), noise)));
  };
  e.default_noise = {as_vector(d.control_std), as_vector(d.state_std)};
  e.route_driver = [](double speed, double side) {
    return robot::square_route_driver(speed, side, /*unicycle=*/false);
  };
  e.route_speed = 3.0;
  e.car_park_noise = true;
  return e;
}

MotionModelEntry unicycle_entry() {
  const robot::UnicycleParams d;
  MotionModelEntry e;
  e.name = "unicycle";
  e.description =
      "a differential-drive robot (unicycle kinematics), turning on the spot when "
      "v = 0";
  e.controls = "u1 = v [m/s], u2 = omega [rad/s]";
  e.keys = {{"dt", "control period [s]", d.dt}};
  e.build = [](const robot::VehicleDeclaration& v, const MotionNoise& noise) {
    return robot::AnyMotionModel(robot::UnicycleModel(unicycle_params(declaring(v), noise)));
  };
  e.default_noise = {as_vector(d.control_std), as_vector(d.state_std)};
  e.route_speed = 1.0;
  return e;
}

std::deque<MotionModelEntry>& registry() {
  // Built on first use, so that a registration at static initialisation in another file finds
  // the built-ins already there, whatever the order the files are initialised in.
  static std::deque<MotionModelEntry> entries{ute_entry(), unicycle_entry()};
  return entries;
}

}  // namespace

const std::deque<MotionModelEntry>& motion_models() { return registry(); }

std::string motion_model_quoted_names() {
  std::string names;
  for (const auto& e : registry())
    names += fmt::format("{}'{}'", names.empty() ? "" : ", ", e.name);
  return names;
}

std::vector<std::string> motion_model_names() {
  std::vector<std::string> names;
  for (const auto& e : registry()) names.push_back(e.name);
  return names;
}

const MotionModelEntry& motion_model(std::string_view name, std::string_view what) {
  for (const auto& e : registry())
    if (e.name == name) return e;
  throw InvalidArgument(
      fmt::format("{}: expected one of {}, got '{}'", what, motion_model_quoted_names(), name));
}

std::string motion_model_choices() {
  const auto names = motion_model_names();
  std::string out;
  for (std::size_t k = 0; k < names.size(); ++k)
    out += (k == 0 ? "" : k + 1 == names.size() ? " or " : ", ") + names[k];
  return out;
}

std::string motion_noise_help() {
  std::string out;
  for (const auto& e : registry()) {
    out += fmt::format("{}{}: {}", out.empty() ? "" : "; ", e.name, e.controls);
    if (e.default_noise.control_sd.size() == 2)
      out += fmt::format(", default {} {}", e.default_noise.control_sd[0],
                         e.default_noise.control_sd[1]);
  }
  return out;
}

void register_motion_model(MotionModelEntry entry) {
  require(!entry.name.empty() && entry.name.find_first_of(" \t=#") == std::string::npos,
          "register_motion_model: expected a name without blanks, '=' or '#', got '{}'",
          entry.name);
  for (const auto& e : registry())
    require(e.name != entry.name, "register_motion_model: the name '{}' is taken", entry.name);
  require(static_cast<bool>(entry.build), "register_motion_model '{}': expected a build function",
          entry.name);
  require(!entry.keys.empty() && entry.keys.front().name == "dt",
          "register_motion_model '{}': expected the `vehicle` key dt (the control period) first",
          entry.name);
  require(entry.default_noise.control_sd.size() == 2 && entry.default_noise.state_sd.size() == 3,
          "register_motion_model '{}': expected a default noise of 2 control and 3 state sds",
          entry.name);
  require(entry.route_speed > 0, "register_motion_model '{}': expected a route speed > 0, got {}",
          entry.name, entry.route_speed);
  registry().push_back(std::move(entry));
}

robot::VehicleDeclaration full_declaration(const MotionModelEntry& entry,
                                           const robot::VehicleDeclaration& declared) {
  robot::VehicleDeclaration v{entry.name, {}};
  for (const VehicleKey& k : entry.keys)
    v.parameters.emplace_back(k.name, declared.parameter(k.name).value_or(k.default_value));
  for (const auto& [key, value] : declared.parameters)
    if (!v.parameter(key)) v.parameters.emplace_back(key, value);  // the build refuses it
  return v;
}

MotionNoise noise_with_defaults(const MotionModelEntry& entry, const MotionNoise& flags) {
  MotionNoise noise = flags;
  if (noise.control_sd.empty()) noise.control_sd = entry.default_noise.control_sd;
  if (noise.state_sd.empty()) noise.state_sd = entry.default_noise.state_sd;
  require(noise.control_sd.size() == 2, "--control-sd: expected 2 values (u1 u2), got {}",
          noise.control_sd.size());
  require(noise.state_sd.size() == 3, "--state-sd: expected 3 values (x y heading), got {}",
          noise.state_sd.size());
  return noise;
}

robot::AnyMotionModel make_motion_model(const MotionModelEntry& entry,
                                        const robot::VehicleDeclaration& declared,
                                        const MotionNoise& flags) {
  return entry.build(full_declaration(entry, declared), noise_with_defaults(entry, flags));
}

}  // namespace implicit::experiments
