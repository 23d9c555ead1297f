#include "experiments/vehicle.hpp"

#include <cstdio>

#include <fmt/format.h>

#include "experiments/motion_models.hpp"
#include "experiments/plural.hpp"
#include "implicit/core/error.hpp"

namespace implicit::experiments {
namespace {

/// What the two controls of a model mean, for the mismatch message.
std::string controls_of(const std::string& model) {
  for (const auto& e : motion_models())
    if (e.name == model) return e.controls;
  return "unknown to this program";
}

/// The noise flags applied to a model's parameters (both models have the same two fields).
template <typename Params>
Params with_noise(Params p, const MotionNoise& noise) {
  if (!noise.control_sd.empty()) {
    require(noise.control_sd.size() == 2, "--control-sd: expected 2 values (u1 u2), got {}",
            noise.control_sd.size());
    p.control_std = Vec<2>(noise.control_sd[0], noise.control_sd[1]);
  }
  if (!noise.state_sd.empty()) {
    require(noise.state_sd.size() == 3, "--state-sd: expected 3 values (x y heading), got {}",
            noise.state_sd.size());
    p.state_std = Vec<3>(noise.state_sd[0], noise.state_sd[1], noise.state_sd[2]);
  }
  p.validate();
  return p;
}

}  // namespace

std::string resolve_model(const std::string& command, const std::string& flag,
                          const std::optional<std::string>& declared,
                          const std::string& data_name) {
  if (!flag.empty()) (void)motion_model(flag, command + " --model");
  if (!declared) return flag.empty() ? "ute" : flag;
  bool known = false;
  for (const auto& e : motion_models()) known = known || e.name == *declared;
  if (!known) {
    throw InvalidArgument(fmt::format(
        "{}: the log '{}' declares vehicle '{}'; this program runs {} (a new one is registered "
        "in experiments/motion_models.hpp, or from Python with "
        "implicit.models.register_motion_model)",
        command, data_name, *declared, motion_model_quoted_names()));
  }
  require(flag.empty() || flag == *declared,
          "{} --model {}: the log '{}' declares vehicle '{}' (controls: {}), not '{}' (controls: "
          "{}); run with --model {}",
          command, flag, data_name, *declared, controls_of(*declared), flag, controls_of(flag),
          *declared);
  return *declared;
}

void warn_vehicle_assumed(const std::string& command, const std::string& data_name,
                          const robot::VehicleDeclaration& used) {
  std::string parameters;
  for (const auto& [key, value] : used.parameters)
    parameters += fmt::format("{}{}={}", parameters.empty() ? "" : " ", key, value);
  fmt::print(stderr,
             "implicit {}: warning: the log '{}' declares no vehicle (no 'vehicle' record): it "
             "runs as the {} with {}, {}; add a 'vehicle' record (docs/formats.md) if another "
             "robot drove it\n",
             command, data_name, used.model, parameters,
             motion_model(used.model, command + " --model").description);
}

void warn_skipped_scans(const std::string& command, const std::string& data_name,
                        const robot::StepSchedule& schedule, double dt) {
  if (schedule.observations_skipped == 0) return;
  const auto skipped = static_cast<long long>(schedule.observations_skipped);
  fmt::print(stderr,
             "implicit {}: warning: {} in {} of '{}' {} not used: each scan is applied at the "
             "control nearest in time, if within half a step ({} s), and at most one scan per "
             "control; write a control record at (or within {} s of) every scan's time "
             "(\"detections_skipped\" in the JSON counts them)\n",
             command, counted(skipped, "detection", "detections"),
             counted(static_cast<long long>(schedule.scans_skipped), "scan", "scans"), data_name,
             skipped == 1 ? "is" : "are", 0.5 * dt, 0.5 * dt);
}

robot::UteParams ute_params(const robot::RobotLog& log, const MotionNoise& noise,
                            robot::UteParams p) {
  return with_noise(log.vehicle ? robot::ute_params(*log.vehicle, p) : p, noise);
}

robot::UnicycleParams unicycle_params(const robot::RobotLog& log, const MotionNoise& noise,
                                      robot::UnicycleParams p) {
  return with_noise(log.vehicle ? robot::unicycle_params(*log.vehicle, p) : p, noise);
}

}  // namespace implicit::experiments
