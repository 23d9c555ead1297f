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

}  // namespace implicit::experiments
