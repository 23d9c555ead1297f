#pragma once
// The pieces the report's sections are built from (apps/report_*.cpp): looking up a
// configuration in results.json, table cells for its values, standard errors and agreement
// cells, and the blocks every section has (status, figure, settings).
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "report.hpp"

namespace implicit::app::report::parts {

using nlohmann::json;
using RunPredicate = std::function<bool(const json& settings)>;

/// The paper's and the reference's numbers the report compares with, and its text: always the
/// bundled data files (data/report/), also for a report rebuilt from an older results.json,
/// whose copies under "paper" and "reference" are kept for provenance only.
struct Numbers {
  json paper;
  json reference;
  Text text;
};
Numbers numbers_of(const json& results);
/// build_report with the numbers and text given (a test records the text keys it looks up).
Document build_report_with(const json& results, const std::filesystem::path& dir,
                           const Numbers& numbers);

/// The first configuration of an experiment whose settings satisfy `pred` (null if none).
const json* find_run(const json& results, const std::string& experiment, const RunPredicate& pred);
/// A configuration that ran and has a result.
bool ok(const json* run);
/// `j[key]`, or null when `j` is no object or has no such key.
const json& get(const json& j, const std::string& key);
/// How many runs a result's means are over: its "runs", or "datasets" for SLAM.
const json& run_count(const json& result);

// ---- Cells --------------------------------------------------------------------------------------

/// "not run" / "failed" / show(result).
std::string cell(const json* run, const std::function<std::string(const json&)>& show);
std::string value_cell(const json* run, const std::string& key, int digits);
std::string int_cell(const json* run, const std::string& key);
/// Appends the row of a configuration without a result: its settings cells `row`, "—", the
/// failure cell ("not run" / "failed"), and "—" to the table's width.
void add_failed_row(Table& t, std::vector<std::string> row, const json& run);
/// "mean (SE se)" of a result's mean over runs `key` and its sd `sd_key`.
std::string mean_se_cell(const json* run, const std::string& key, const std::string& sd_key,
                         int digits);
/// ESS/M from a result's `ess_mean` (a sample count or already divided by M).
std::string ess_fraction_cell(const json* run, int m, int digits);
/// "mean ± sd" of transcribed numbers ("–" without a mean).
std::string pm(const json& mean, const json& sd, int digits);
/// array[i] with `digits` decimals, "–" when out of range.
std::string at(const json& array, std::size_t i, int digits);

// ---- Agreement ----------------------------------------------------------------------------------

/// Our estimate of prefix_mean from a configuration (its SE from prefix_std and the run count).
Estimate ours_estimate(const json* run, const std::string& prefix);
/// The reference's mean with SE sd/√n (NaN SE when sd or n is missing).
Estimate reference_estimate(const json& mean, const json& sd, const json& n);
/// A fraction p of n trials: SE √(p(1 − p)/n).
Estimate fraction_estimate(const json& p, const json& n);
/// The test as the report states it once, in its introduction.
std::string agreement_statement(const Text& text);

// ---- Blocks -------------------------------------------------------------------------------------

std::string status_of(const json& results, const std::string& experiment);
/// Figure block: the PNG when the script succeeded, otherwise the reason; its caption is the
/// text `caption_key`.
void figure(Document& doc, const json& results, const Text& text, int n,
            const std::string& caption_key);
void settings_list(Document& doc, const json& results, const Text& text,
                   const std::string& experiment);
/// A section of one table and one figure: the heading, the experiment's status, the text
/// "<prefix>.intro", `table`, "<prefix>.reading", figure `figure_number` with its caption
/// "<prefix>.figure<N>", and the settings list.
void table_and_figure_section(Document& doc, const json& results, const Text& text,
                              const std::string& experiment, const std::string& prefix,
                              const Table& table, int figure_number);
void experiment_status(Document& doc, const json& results, const Text& text,
                       const std::string& experiment);

// ---- Sections -----------------------------------------------------------------------------------

void slit_section(Document& doc, const json& results, const Numbers& numbers);
void arm_section(Document& doc, const json& results, const Numbers& numbers);
void himmelblau_section(Document& doc, const json& results, const Numbers& numbers,
                        const std::filesystem::path& dir);
void mcl_section(Document& doc, const json& results, const Numbers& numbers);
void slam_section(Document& doc, const json& results, const Numbers& numbers);
void proposal_gain_section(Document& doc, const json& results, const Numbers& numbers);
void global_localization_section(Document& doc, const json& results, const Numbers& numbers);
void laser_mcl_section(Document& doc, const json& results, const Numbers& numbers);
void grid_slam_section(Document& doc, const json& results, const Numbers& numbers);
void da_section(Document& doc, const json& results, const Numbers& numbers);

}  // namespace implicit::app::report::parts
