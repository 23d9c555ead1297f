#pragma once
// `implicit mcl --init global` and `--kidnap-at`: the runs of exp_mcl_global.cpp.
#include <nlohmann/json.hpp>

#include "experiments.hpp"
#include "implicit/filter/localization.hpp"
#include "implicit/robot/unicycle_model.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::app {

/// Refuses settings a global or kidnapping run cannot honour (before any data is loaded).
void check_global_settings(const MclSettings& s);

/// Keys: global_success_rate or kidnap_recovery_rate, time_to_converge_s_median or
/// recovery_time_s_median, particles_mean, particles_peak, cpu_ms_per_step, per-run lists.
nlohmann::json run_mcl_global(const MclSettings& s, const RunContext& ctx,
                              const robot::UteModel& model, const robot::RangeBearingSensor& sensor,
                              const filter::LocalizationProblem& problem);
nlohmann::json run_mcl_global(const MclSettings& s, const RunContext& ctx,
                              const robot::UnicycleModel& model,
                              const robot::RangeBearingSensor& sensor,
                              const filter::LocalizationProblem& problem);

}  // namespace implicit::app
