#pragma once
// Which robot a command runs: --model against the `vehicle` record a log declares, and the
// motion models built from the declaration and the noise flags (shared by mcl, slam, simulate).
#include <optional>
#include <string>
#include <vector>

#include "implicit/robot/log_format.hpp"
#include "implicit/robot/unicycle_model.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::experiments {

/// The model to run: `flag` (a registered model's name, or empty) checked against the model the
/// data declare. Empty flag: the declared model, "ute" for data that declare none (the Car Park
/// convention). Throws InvalidArgument (exit 1) naming the command, the data and both models on
/// a mismatch.
std::string resolve_model(const std::string& command, const std::string& flag,
                          const std::optional<std::string>& declared, const std::string& data_name);

/// A log that declares no vehicle runs as `used` (the Car Park's Ute unless --model says another
/// model). Numbers of the wrong robot look like results, so this is said on stderr whatever
/// --quiet and --json say, and the command's JSON records "vehicle_assumed": true.
/// Says on stderr how many detections (in how many scans) the step schedule left out and how to
/// keep them; nothing when none was.
void warn_skipped_scans(const std::string& command, const std::string& data_name,
                        const robot::StepSchedule& schedule, double dt);
void warn_vehicle_assumed(const std::string& command, const std::string& data_name,
                          const robot::VehicleDeclaration& used);

/// The noise flags of a command: empty vectors keep the model's defaults.
struct MotionNoise {
  std::vector<double> control_sd;  ///< sd of u1, u2
  std::vector<double> state_sd;    ///< sd of x, y, heading (per sqrt(s))
};

/// UteParams from the log's declaration (if any) and the noise flags.
robot::UteParams ute_params(const robot::RobotLog& log, const MotionNoise& noise,
                            robot::UteParams base = {});
/// UnicycleParams from the log's declaration (if any) and the noise flags.
robot::UnicycleParams unicycle_params(const robot::RobotLog& log, const MotionNoise& noise,
                                      robot::UnicycleParams base = {});

}  // namespace implicit::experiments
