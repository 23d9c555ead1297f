#pragma once
// The experiments the subcommands run (experiments/: control, landmark MCL and SLAM, proposal
// gain), by their names in implicit::app. The command line parses its flags into these settings
// and prints what they return.

#include "experiments/control.hpp"
#include "experiments/landmark_mcl.hpp"
#include "experiments/landmark_slam.hpp"
#include "experiments/proposal_gain.hpp"
#include "experiments/run_context.hpp"

namespace implicit::app {

using experiments::ArmSettings;
using experiments::HimmelblauSettings;
using experiments::MclSettings;
using experiments::ProposalGainSettings;
using experiments::SlamSettings;
using experiments::SlitSettings;

using experiments::run_arm;
using experiments::run_himmelblau;
using experiments::run_mcl;
using experiments::run_proposal_gain;
using experiments::run_slam;
using experiments::run_slit;

}  // namespace implicit::app
