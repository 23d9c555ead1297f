// The settings' choices from and to text (choices.hpp): the one place where their names are
// spelled, with the messages the command line's and Python's bad-input tests check.
#include "experiments/choices.hpp"

#include <array>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit::experiments {
namespace {

template <typename E, std::size_t N>
using Names = std::array<std::pair<E, std::string_view>, N>;

/// The enum named `text`, or InvalidArgument with `message` (one {} for the text).
template <typename E, std::size_t N>
E parse(const Names<E, N>& names, std::string_view text, const char* message) {
  for (const auto& [value, name] : names)
    if (name == text) return value;
  throw InvalidArgument(fmt::format(fmt::runtime(message), text));
}

template <typename E, std::size_t N>
std::string_view name(const Names<E, N>& names, E value) {
  for (const auto& [v, n] : names)
    if (v == value) return n;
  return "?";
}

constexpr Names<control::SlitEstimator, 3> kSlitModes{
    {{control::SlitEstimator::kPaper, "paper"},
     {control::SlitEstimator::kFrozenWall, "corrected"},
     {control::SlitEstimator::kPlainFd, "plain"}}};
constexpr Names<SlitImplementation, 2> kSlitEstimators{
    {{SlitImplementation::kGeneric, "generic"}, {SlitImplementation::kWallSpace, "wall-space"}}};
constexpr Names<control::ArmController, 2> kArmEstimators{
    {{control::ArmController::kGeneric, "generic"},
     {control::ArmController::kClosedForm, "closed-form"}}};
constexpr Names<NoiseConfig, 2> kConfigs{{{NoiseConfig::kA, "A"}, {NoiseConfig::kB, "B"}}};
constexpr Names<filter::ImplicitMap, 2> kMaps{
    {{filter::ImplicitMap::kLinear, "linear"}, {filter::ImplicitMap::kRandom, "random"}}};
constexpr Names<Sigma2Reading, 2> kSigma2{
    {{Sigma2Reading::kVariance, "variance"}, {Sigma2Reading::kStd, "std"}}};
constexpr Names<MclTruth, 2> kMclTruths{
    {{MclTruth::kGps, "gps"}, {MclTruth::kReference, "reference"}}};
constexpr Names<slam::TruthMode, 2> kSlamTruths{
    {{slam::TruthMode::kPaper, "paper"}, {slam::TruthMode::kConsistent, "consistent"}}};

}  // namespace

control::SlitEstimator parse_slit_mode(std::string_view text) {
  return parse(kSlitModes, text, "slit mode: expected 'paper', 'corrected' or 'plain', got '{}'");
}
std::string_view name_of(control::SlitEstimator mode) { return name(kSlitModes, mode); }

SlitImplementation parse_slit_estimator(std::string_view text) {
  return parse(kSlitEstimators, text,
               "slit --estimator: expected 'wall-space' or 'generic', got '{}'");
}
std::string_view name_of(SlitImplementation estimator) { return name(kSlitEstimators, estimator); }

control::ArmController parse_arm_estimator(std::string_view text) {
  return parse(kArmEstimators, text,
               "arm --estimator: expected 'closed-form' or 'generic', got '{}'");
}
std::string_view name_of(control::ArmController estimator) {
  return name(kArmEstimators, estimator);
}

NoiseConfig parse_noise_config(std::string_view text) {
  return parse(kConfigs, text, "mcl --config: expected 'A' or 'B', got '{}'");
}
std::string_view name_of(NoiseConfig config) { return name(kConfigs, config); }

filter::ImplicitMap parse_implicit_map(std::string_view text) {
  return parse(kMaps, text, "mcl --map: expected 'linear' or 'random', got '{}'");
}
std::string_view name_of(filter::ImplicitMap map) { return name(kMaps, map); }

Sigma2Reading parse_sigma2(std::string_view text) {
  return parse(kSigma2, text, "mcl --sigma2: expected 'variance' or 'std', got '{}'");
}
std::string_view name_of(Sigma2Reading reading) { return name(kSigma2, reading); }

MclTruth parse_mcl_truth(std::string_view text) {
  return parse(kMclTruths, text, "mcl --truth: expected 'gps' or 'reference', got '{}'");
}
std::string_view name_of(MclTruth truth) { return name(kMclTruths, truth); }

slam::TruthMode parse_slam_truth(std::string_view text) {
  return parse(kSlamTruths, text, "--truth: expected paper|consistent, got '{}'");
}
std::string_view name_of(slam::TruthMode truth) { return name(kSlamTruths, truth); }

std::vector<std::string> ChoiceSet::names() const {
  std::vector<std::string> out;
  for (const Choice& c : choices) out.emplace_back(c.name);
  return out;
}

std::string ChoiceSet::help() const {
  std::string out;
  for (const Choice& c : choices)
    out += fmt::format("{}{}: {}", out.empty() ? "" : "; ", c.name, c.meaning);
  return out;
}

std::string ChoiceSet::quoted() const {
  std::string out;
  for (std::size_t k = 0; k < choices.size(); ++k)
    out += fmt::format("{}'{}'", k == 0 ? "" : (k + 1 == choices.size() ? " or " : ", "),
                       choices[k].name);
  return out;
}

std::string_view ChoiceSet::check(std::string_view text, std::string_view what) const {
  for (const Choice& c : choices)
    if (c.name == text) return c.name;
  throw InvalidArgument(
      fmt::format("{}: expected {}, got '{}'", what.empty() ? setting : what, quoted(), text));
}

const ChoiceSet& mcl_methods() {
  static const ChoiceSet set{"mcl --method",
                             {{"standard", "bootstrap MCL (the motion model is the proposal)"},
                              {"implicit", "implicit sampling per particle"}}};
  return set;
}

const ChoiceSet& sensors() {
  static const ChoiceSet set{
      "--sensor",
      {{"landmark", "range-bearing detections of point landmarks (Car Park, robot logs)"},
       {"laser",
        "2-D laser scans on an occupancy grid (a CARMEN log, a robot log with laser "
        "records, or a ROS bag)"}}};
  return set;
}

const ChoiceSet& laser_models() {
  static const ChoiceSet set{
      "mcl --laser-model",
      {{"likelihood-field", "distances to the nearest obstacle (both proposals)"},
       {"beam", "ray casting (the bootstrap proposal only)"}}};
  return set;
}

const ChoiceSet& landmark_slam_methods() {
  static const ChoiceSet set{"slam --method",
                             {{"ekf", "EKF-SLAM"},
                              {"fastslam1", "FastSLAM 1.0 (the motion model is the proposal)"},
                              {"fastslam2", "FastSLAM 2.0 (the EKF-linearised optimal proposal)"},
                              {"implicit", "implicit sampling of the pose (the paper's SLAM)"},
                              {"implicit-rb", "implicit sampling, Rao-Blackwellised"}}};
  return set;
}

const ChoiceSet& grid_slam_methods() {
  static const ChoiceSet set{
      "slam --sensor laser --method",
      {{"bootstrap", "the motion model is the proposal"},
       {"gmapping", "scan matching against the particle's map, GMapping's approximate weights"},
       {"implicit", "implicit sampling of the pose against the particle's map, exact weights"}}};
  return set;
}

const ChoiceSet& da_methods() {
  static const ChoiceSet set{
      "da --method",
      {{"bootstrap", "bootstrap particle filter"},
       {"implicit", "implicit particle filter"},
       {"enkf", "stochastic EnKF (perturbed observations)"},
       {"etkf", "square-root EnKF (ETKF)"},
       {"implicit-smoother", "implicit smoother over a window of L cycles"}}};
  return set;
}

std::vector<const ChoiceSet*> choice_sets() {
  return {&mcl_methods(),           &sensors(),           &laser_models(),
          &landmark_slam_methods(), &grid_slam_methods(), &da_methods()};
}

}  // namespace implicit::experiments
