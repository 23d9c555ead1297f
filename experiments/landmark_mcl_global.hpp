#pragma once
// `implicit mcl --init global` and `--kidnap-at`: the runs of exp_mcl_global.cpp.
#include <nlohmann/json.hpp>

#include "experiments/landmark_mcl.hpp"
#include "implicit/filter/localization.hpp"
#include "implicit/robot/any_motion_model.hpp"
#include "implicit/robot/unicycle_model.hpp"
#include "implicit/robot/ute_model.hpp"

namespace implicit::experiments {

/// Refuses settings a global or kidnapping run cannot honour (before any data is loaded).
void check_global_settings(const MclSettings& s);

/// --trajectory (run 0's estimate) and --truth-trajectory (the truth, where known) as TUM files;
/// nothing when neither is set (exp_mcl.cpp).
void write_mcl_tum_files(const MclSettings& s, const filter::LocalizationProblem& problem,
                         const filter::LocalizationRun& run);

/// Keys: global_success_rate or kidnap_recovery_rate, time_to_converge_s_median or
/// recovery_time_s_median, particles_mean, particles_peak, cpu_ms_per_step, per-run lists.
nlohmann::json run_mcl_global(const MclSettings& s, const RunContext& ctx,
                              const robot::UteModel& model, const robot::RangeBearingSensor& sensor,
                              const filter::LocalizationProblem& problem);
nlohmann::json run_mcl_global(const MclSettings& s, const RunContext& ctx,
                              const robot::UnicycleModel& model,
                              const robot::RangeBearingSensor& sensor,
                              const filter::LocalizationProblem& problem);
/// Any other registered model (experiments/motion_models.hpp), through its indirect calls.
nlohmann::json run_mcl_global(const MclSettings& s, const RunContext& ctx,
                              const robot::AnyMotionModel& model,
                              const robot::RangeBearingSensor& sensor,
                              const filter::LocalizationProblem& problem);

}  // namespace implicit::experiments
