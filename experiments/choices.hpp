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

#include <string>
#include <string_view>
#include <vector>

#include "experiments/slit_table.hpp"
#include "implicit/control/double_slit.hpp"
#include "implicit/control/robot_arm.hpp"
#include "implicit/filter/proposals.hpp"
#include "implicit/slam/dataset.hpp"

namespace implicit::experiments {

/// One choice of a setting that takes a name: the name and what it means.
struct Choice {
  std::string_view name;
  std::string_view meaning;
};

/// The methods, proposals and sensor models a setting chooses from, listed once: the command
/// line's check and help, the experiments' and Python's checks, and docs/cli.md's table of
/// choices come from here (a test checks the table, and that each name parses where the run
/// parses it).
struct ChoiceSet {
  std::string_view setting;  ///< "mcl --method": the flag, as the messages name it
  std::vector<Choice> choices;

  std::vector<std::string> names() const;
  /// "standard: bootstrap MCL; implicit: implicit sampling per particle"
  std::string help() const;
  /// "'a' or 'b'", "'a', 'b' or 'c'"
  std::string quoted() const;
  /// `text` when it names a choice; else InvalidArgument "`what`: expected 'a' or 'b', got
  /// 'text'" (what defaults to the setting).
  std::string_view check(std::string_view text, std::string_view what = {}) const;
};

const ChoiceSet& mcl_methods();            ///< mcl --method: standard, implicit
const ChoiceSet& sensors();                ///< mcl and slam --sensor: landmark, laser
const ChoiceSet& laser_models();           ///< mcl --laser-model: likelihood-field, beam
const ChoiceSet& landmark_slam_methods();  ///< slam --method: ekf ... implicit-rb
const ChoiceSet& grid_slam_methods();      ///< slam --sensor laser --method: bootstrap ...
const ChoiceSet& da_methods();             ///< da --method: bootstrap ... implicit-smoother
/// Every set above, in that order (docs/cli.md's table of choices lists them so).
std::vector<const ChoiceSet*> choice_sets();

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
