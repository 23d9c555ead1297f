// The prediction gate on labelled detections (robot/landmark_observation.hpp, gate();
// filter/monte_carlo_localization.hpp, step_observed): an absurd labelled detection is left out
// and counted, for both proposals; the step then equals a step without it, bit for bit; with the
// gate off it moves the estimate; a spread-out cloud gates nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "implicit/core/error.hpp"
#include "implicit/filter/particle_filter.hpp"

namespace implicit::filter {
namespace {

using robot::LandmarkMap;
using robot::RangeBearingSensor;
using robot::UteModel;

LandmarkMap label_gate_map() {
  LandmarkMap m;
  m.add(10, Landmark(5.0, 0.0));
  m.add(11, Landmark(0.0, 5.0));
  m.add(12, Landmark(-5.0, 0.0));
  return m;
}

FilterOptions label_gate_options(double gate) {
  FilterOptions o;
  o.particles = 200;
  o.seed = 7;
  o.association.label_gate = gate;
  return o;
}

// The detections of map indices 0 and 1 as seen from the predicted pose (so they are
// consistent), and optionally index 2 at 500 m where it is 5 m away.
std::vector<LabelledMeasurement> label_gate_detections(const UteModel& model, const Control& u,
                                                       bool absurd) {
  const RangeBearingSensor sensor;
  const Pose f = model.predict(Pose::Zero(), u);
  const LandmarkMap map = label_gate_map();
  std::vector<LabelledMeasurement> z;
  for (std::size_t k = 0; k < 2; ++k)
    z.push_back({sensor.predict(f, map.position(k)), static_cast<int>(k)});
  if (absurd) {
    Measurement far = sensor.predict(f, map.position(2));
    far(0) = 500.0;
    z.push_back({far, 2});
  }
  return z;
}

template <typename Proposal>
StepSummary label_gate_step(Proposal proposal, double gate, bool absurd, double spread = 0.1) {
  const UteModel model;
  const Control u(1.0, 0.0);
  ParticleFilter pf(model, RangeBearingSensor(), label_gate_map(), proposal,
                    label_gate_options(gate));
  pf.initialize(Pose::Zero(),
                Vec<3>(spread, spread, 0.2 * spread).cwiseAbs2().asDiagonal().toDenseMatrix());
  return pf.step(u, label_gate_detections(model, u, absurd));
}

template <typename Proposal>
void expect_absurd_label_left_out(Proposal proposal) {
  const StepSummary clean = label_gate_step(proposal, robot::kLabelGateDefault, false);
  const StepSummary gated = label_gate_step(proposal, robot::kLabelGateDefault, true);
  EXPECT_EQ(clean.gated, 0);
  EXPECT_EQ(gated.gated, 1);
  // The step read the two consistent detections only: the same draws, the same numbers.
  EXPECT_EQ(gated.mean, clean.mean);
  EXPECT_EQ(gated.ess, clean.ess);
  EXPECT_EQ(gated.log_likelihood_increment, clean.log_likelihood_increment);
}

TEST(LabelGate, AnAbsurdLabelledDetectionIsLeftOutForTheBootstrap) {
  expect_absurd_label_left_out(BootstrapProposal{});
}

TEST(LabelGate, AnAbsurdLabelledDetectionIsLeftOutForTheImplicitProposal) {
  expect_absurd_label_left_out(ImplicitProposal{});
}

TEST(LabelGate, WithTheGateOffTheAbsurdDetectionMovesTheImplicitEstimate) {
  const StepSummary clean = label_gate_step(ImplicitProposal{}, robot::kLabelGateDefault, false);
  const StepSummary trusted = label_gate_step(ImplicitProposal{}, 0.0, true);
  EXPECT_EQ(trusted.gated, 0);
  // A 495 m range residual against a prior of 0.1 m: the minimum moves by metres, not cm.
  EXPECT_GT((trusted.mean.head<2>() - clean.mean.head<2>()).norm(), 1.0);
}

TEST(LabelGate, ASpreadOutCloudGatesNothing) {
  // A cloud 1 km wide (a global start) could produce a 500 m range: nothing is left out.
  const StepSummary wide =
      label_gate_step(BootstrapProposal{}, robot::kLabelGateDefault, true, 1000.0);
  EXPECT_EQ(wide.gated, 0);
}

TEST(LabelGate, TheGateIsCheckedAtConstruction) {
  for (double bad : {-1.0, std::nan(""), HUGE_VAL}) {
    robot::AssociationOptions a;
    a.label_gate = bad;
    try {
      robot::LandmarkObservation<RangeBearingSensor> model(RangeBearingSensor(), label_gate_map(),
                                                           a);
      ADD_FAILURE() << "accepted label gate " << bad;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("label gate"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace implicit::filter
