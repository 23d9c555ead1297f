#pragma once
// The choices of the landmark and control experiments' settings as enums: each parsed from its
// text in one place (choices.cpp), which the command line (after its own check of the flag) and
// the Python module both call, and named by name_of for the JSON, the CSV file names and the
// --resume keys. A text that is not one of the names is an InvalidArgument naming the flag and
// the names it takes.
//
//   SlitSettings s;
//   s.mode = parse_slit_mode("paper");       // control::SlitEstimator::kPaper
//   name_of(s.mode);                         // "paper"

#include <string_view>

#include "experiments/slit_table.hpp"
#include "implicit/control/double_slit.hpp"
#include "implicit/control/robot_arm.hpp"
#include "implicit/filter/proposals.hpp"
#include "implicit/slam/dataset.hpp"

namespace implicit::experiments {

/// MCL's noise setting (spec §3.9): A is the paper's P = 0.5, B is P = 0.1.
enum class NoiseConfig { kA, kB };
/// The reading of Table 7's Sigma2 entries: as variances (spec E27) or as standard deviations.
enum class Sigma2Reading { kVariance, kStd };
/// What MCL's runs are scored against: the GPS fixes, or a GPS-aided reference run.
enum class MclTruth { kGps, kReference };

/// `implicit slit --mode`: "paper" (estimator P), "corrected" (W2, frozen wall) or "plain".
control::SlitEstimator parse_slit_mode(std::string_view text);
std::string_view name_of(control::SlitEstimator mode);
/// `implicit slit --estimator`: "generic" or "wall-space".
SlitImplementation parse_slit_estimator(std::string_view text);
std::string_view name_of(SlitImplementation estimator);
/// `implicit arm --estimator`: "generic" or "closed-form".
control::ArmController parse_arm_estimator(std::string_view text);
std::string_view name_of(control::ArmController estimator);

/// `implicit mcl --config`: "A" or "B".
NoiseConfig parse_noise_config(std::string_view text);
std::string_view name_of(NoiseConfig config);
/// `implicit mcl --implicit-map` (and --map for landmarks): "linear" or "random".
filter::ImplicitMap parse_implicit_map(std::string_view text);
std::string_view name_of(filter::ImplicitMap map);
/// `implicit mcl --sigma2`: "variance" or "std".
Sigma2Reading parse_sigma2(std::string_view text);
std::string_view name_of(Sigma2Reading reading);
/// `implicit mcl --truth`: "gps" or "reference".
MclTruth parse_mcl_truth(std::string_view text);
std::string_view name_of(MclTruth truth);

/// `implicit slam --truth`: "paper" (noise-free) or "consistent".
slam::TruthMode parse_slam_truth(std::string_view text);
std::string_view name_of(slam::TruthMode truth);

}  // namespace implicit::experiments
