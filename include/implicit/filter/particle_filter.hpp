#pragma once
// Monte Carlo localization on range-bearing detections of point landmarks: the one filter
// (monte_carlo_localization.hpp) with the landmark observation model
// (robot/landmark_observation.hpp), under the constructor and step() of the landmark data.
//
//   using namespace implicit;
//   filter::ParticleFilter pf(robot::UteModel(), robot::RangeBearingSensor(), map,
//                             filter::ImplicitProposal{}, options);  // FilterOptions
//   pf.initialize(mean, covariance);
//   for (const auto& step : steps) {
//     const filter::StepSummary& s = pf.step(step.u, detections);   // detections may be empty
//     ... s.mean, s.covariance, s.ess, s.resampled, s.log_likelihood_increment ...
//   }
//
// Steps without detections only predict; the weights stay unchanged. FilterOptions::association
// sets the model's gate, clutter and minimum range. The step, the weights, KLD-sampling and
// recovery are MonteCarloLocalization's; see there for the per-step outputs.

#include <span>
#include <utility>

#include "implicit/filter/monte_carlo_localization.hpp"
#include "implicit/filter/proposals.hpp"
#include "implicit/robot/landmark_map.hpp"
#include "implicit/robot/landmark_observation.hpp"
#include "implicit/robot/models.hpp"

namespace implicit::filter {

template <robot::MotionModel Motion, robot::LandmarkSensor Sensor, typename Proposal>
class ParticleFilter
    : public MonteCarloLocalization<Motion, robot::LandmarkObservation<Sensor>, Proposal> {
  using Base = MonteCarloLocalization<Motion, robot::LandmarkObservation<Sensor>, Proposal>;

 public:
  using Observation = robot::LandmarkObservation<Sensor>;
  using Detections = typename Observation::Prepared;
  using Control = typename Base::Control;
  using typename Base::Context;

  ParticleFilter(Motion motion, Sensor sensor, robot::LandmarkMap map, Proposal proposal,
                 FilterOptions options)
      : Base(std::move(motion), Observation(std::move(sensor), std::move(map), options.association),
             std::move(proposal), options) {}

  /// The detections z as the model reads them, unchecked (for a global initialisation, which
  /// samples the pose from the detections alone). Valid while z and the filter live.
  Detections context(std::span<const LabelledMeasurement> z) const {
    return this->observation().view(z);
  }

  const Sensor& sensor() const { return this->observation().sensor(); }
  const robot::LandmarkMap& map() const { return this->observation().map(); }

  /// One motion step with control u and the detections seen after it (empty: predict only).
  const StepSummary& step(const Control& u, std::span<const LabelledMeasurement> z = {}) {
    if (z.empty()) return Base::step(u);
    return Base::step(u, z,
                      "particle filter");  // labelled detections gated (observation_model.hpp)
  }

  /// A step that also weights by a position fix (GPS) of the new state.
  const StepSummary& step(const Control& u, std::span<const LabelledMeasurement> z,
                          const PositionFix& fix) {
    validate(fix);
    if (z.empty()) return Base::step_prepared(u, nullptr, &fix);
    return Base::step(u, z, fix, "particle filter");
  }
};

}  // namespace implicit::filter
