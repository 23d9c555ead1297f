// The `implicit` command line: version, usage errors (exit code 2, the flag named), the options
// every subcommand shares, and the plot helpers' loud failures on bad figure data.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::run_shell;
using implicit::test::TempDir;

TEST(Cli, VersionPrintsVersionAndCommit) {
  const auto r = run_cli("--version");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(
      std::regex_search(r.out, std::regex(R"(implicit \d+\.\d+\.\d+ \(commit [0-9a-z]+\))")))
      << r.out;
}

TEST(Cli, UnknownFlagNamesTheFlagAndExits2) {
  const auto r = run_cli("reproduce --no-such-flag");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--no-such-flag"), std::string::npos) << r.err;
}

TEST(Cli, UnknownSubcommandExits2) {
  const auto r = run_cli("no-such-command");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("no-such-command"), std::string::npos) << r.err;
}

TEST(Cli, OutOfRangeValueNamesTheFlagAndTheRange) {
  const auto r = run_cli("reproduce --threads -3");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--threads"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1024"), std::string::npos) << "accepted range missing: " << r.err;
}

TEST(Cli, NonNumericValueNamesTheFlag) {
  const auto r = run_cli("reproduce --seed abc");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--seed"), std::string::npos) << r.err;
}

TEST(Cli, UnknownExperimentNamesTheFlagAndTheChoices) {
  const auto r = run_cli("reproduce --only slit,nonsense");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--only"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("himmelblau"), std::string::npos) << "choices missing: " << r.err;
}

// Every subcommand shares --seed --json --out --threads --quiet --help and shows examples.
TEST(Cli, EverySubcommandHasTheCommonOptionsAndExamples) {
  const auto top = run_cli("--help");
  ASSERT_EQ(top.code, 0);
  const auto start = top.out.find("Subcommands:");
  ASSERT_NE(start, std::string::npos) << top.out;
  std::istringstream lines(top.out.substr(start));
  std::string line;
  std::getline(lines, line);  // "Subcommands:"
  std::set<std::string> names;
  while (std::getline(lines, line)) {
    std::smatch m;
    if (!std::regex_search(line, m, std::regex(R"(^  ([a-z][a-z0-9-]*)\s)"))) break;
    names.insert(m[1]);
  }
  ASSERT_TRUE(names.count("reproduce")) << top.out;
  for (const auto& name : names) {
    const auto r = run_cli(name + " --help");
    EXPECT_EQ(r.code, 0) << name;
    for (const char* option : {"--seed", "--json", "--out", "--threads", "--quiet", "--help"})
      EXPECT_NE(r.out.find(option), std::string::npos) << name << " lacks " << option;
    EXPECT_NE(r.out.find("Examples:"), std::string::npos) << name << " has no examples";
  }
}

// `implicit mcl` places every detection with the ground-truth pose and reports its distance to the
// nearest surveyed beacon. This is deterministic (data and models only): spec §3.8 measures a
// median of 0.21 m and 96 % within 0.5 m under the dead-reckoned pose over the first 40 s; the GPS
// track over the whole run must do at least as well, or extraction or sensor model is broken.
TEST(Cli, MclChecksTheBeaconDetectionsAgainstTheSurvey) {
  TempDir dir("mcl_detections");
  const auto r =
      run_cli("mcl --runs 1 --particles 20 --json --quiet --out '" + dir.path().string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("detection_check")) << r.out;
  const auto& c = j["detection_check"];
  EXPECT_GT(c["detections_placed"].get<int>(), 500);
  EXPECT_LT(c["distance_to_nearest_beacon_median_m"].get<double>(), 0.21);
  EXPECT_GT(c["within_0_5_m_fraction"].get<double>(), 0.96);
  std::ifstream csv(dir.path() / "mcl_detections.csv");
  int lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, 1 + j["detections_total"].get<int>());
}

// `implicit slam` exposes the filters' laser model and association: the JSON echoes what the
// filter used, 0 means the spec's value (bit-identical to leaving the option out), a given
// value reaches the filter (the estimate changes), a negative one is a usage error.
TEST(Cli, SlamSensorNoiseGateAndNewLandmarkDensityReachTheFilter) {
  const std::string base = "slam --method fastslam1 -M 10 --datasets 1 --json --quiet";
  const auto d = run_cli(base);
  ASSERT_EQ(d.code, 0) << d.err;
  const auto jd = nlohmann::json::parse(d.out);
  constexpr double kPi = 3.14159265358979323846;
  EXPECT_NEAR(jd["range_sd_m"].get<double>(), std::sqrt(0.05), 1e-12);
  EXPECT_NEAR(jd["bearing_sd_deg"].get<double>(), std::sqrt(0.05 * kPi / 180.0) * 180.0 / kPi,
              1e-12);
  EXPECT_EQ(jd["gate_chi2"].get<double>(), 9.21);
  EXPECT_NEAR(jd["new_landmark_density"].get<double>(), 1.0 / (15.0 * kPi), 1e-15);

  const auto z = run_cli(base + " --range-sd 0 --bearing-sd 0 --gate-chi2 0");
  ASSERT_EQ(z.code, 0) << z.err;
  EXPECT_EQ(nlohmann::json::parse(z.out)["map_shape_m"], jd["map_shape_m"]);

  const auto c = run_cli(base +
                         " --association ml --range-sd 0.5 --bearing-sd 3 --gate-chi2 16 "
                         "--new-landmark-density 0.01");
  ASSERT_EQ(c.code, 0) << c.err;
  const auto jc = nlohmann::json::parse(c.out);
  EXPECT_EQ(jc["range_sd_m"].get<double>(), 0.5);
  EXPECT_NEAR(jc["bearing_sd_deg"].get<double>(), 3.0, 1e-12);
  EXPECT_EQ(jc["gate_chi2"].get<double>(), 16.0);
  EXPECT_EQ(jc["new_landmark_density"].get<double>(), 0.01);
  EXPECT_NE(jc["map_shape_m"], jd["map_shape_m"]);

  const auto bad = run_cli(base + " --range-sd -1");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--range-sd"), std::string::npos) << bad.err;
}

// A log without a true map (like Victoria Park): the map metrics cannot be computed, so they are
// null in the JSON and "n/a" in the text, not an error of 0.000 m that looks like a result; the
// path, which has truth, is still scored.
TEST(Cli, SlamWithoutATrueMapReportsNoMapMetrics) {
  TempDir dir("slam_no_map");
  std::string log =
      "vehicle ute dt=0.025 L=2.83 H=0.76 a=3.78 b=0.5\ninitial 0 0 0 0 0.1 0.1 0.01\n";
  for (int n = 1; n <= 80; ++n) {
    const std::string t = std::to_string(0.025 * n);
    log += "control " + t + " 2 0\n";
    if (n % 8 == 0) log += "scan " + t + " 2\nobs 6 1.2\nobs 9 0.6\n";  // unlabelled: no map
    log += "truth " + t + " " + std::to_string(0.05 * n) + " 0\n";
  }
  implicit::test::write_file(dir.path() / "no_map.log", log);
  const std::string args =
      "slam --method fastslam2 -M 5 --association ml --datasets 1 --quiet "
      "--data " +
      (dir.path() / "no_map.log").string();
  const auto j = run_cli(args + " --json");
  ASSERT_EQ(j.code, 0) << j.err;
  const auto r = nlohmann::json::parse(j.out);
  for (const char* key : {"rmse_map_m", "rmse_map_m_std", "map_shape_m", "map_shape_m_std"})
    EXPECT_TRUE(r[key].is_null()) << key << ": " << r[key];
  EXPECT_GT(r["landmarks_mean"].get<double>(), 0.0);
  EXPECT_TRUE(r["rmse_pose_m"].is_number()) << r["rmse_pose_m"];
  const auto text = run_cli(args);
  ASSERT_EQ(text.code, 0) << text.err;
  EXPECT_NE(text.out.find("map RMSE n/a, map shape n/a,"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("pose RMSE 0."), std::string::npos) << text.out;
}

// `implicit mcl --init global --duration D` filters only the log's first D seconds (from the first
// control): fewer steps than the whole log, and the error traces end just before D.
TEST(Cli, MclGlobalDurationCutsTheLog) {
  const std::string base = "mcl --init global --method standard -M 20 --runs 1 --json --quiet";
  const auto whole = run_cli(base);
  ASSERT_EQ(whole.code, 0) << whole.err;
  TempDir dir("mcl_duration");
  const auto cut = run_cli(base + " --duration 20 --out '" + dir.path().string() + "'");
  ASSERT_EQ(cut.code, 0) << cut.err;
  const int all_steps = nlohmann::json::parse(whole.out)["steps"].get<int>();
  const int cut_steps = nlohmann::json::parse(cut.out)["steps"].get<int>();
  EXPECT_GT(cut_steps, 0);
  EXPECT_LT(cut_steps, all_steps);
  std::ifstream csv(dir.path() / "mcl_global_standard_M20_errors.csv");
  ASSERT_TRUE(csv) << "no errors CSV";
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "run,start_s,time_s,error_m,particles");
  double last = -1.0;
  int rows = 0;
  while (std::getline(csv, line)) {
    std::stringstream fields(line);
    std::string run, start, time;
    std::getline(fields, run, ',');
    std::getline(fields, start, ',');
    std::getline(fields, time, ',');
    last = std::stod(time);
    EXPECT_LT(last, 20.0) << line;
    ++rows;
  }
  EXPECT_GT(rows, 0);
  // The log's steps are 25 ms apart; a cut that stopped well short of D would be a bug too.
  EXPECT_GT(last, 19.0);
  EXPECT_EQ(run_cli(base + " --duration -1").code, 2);
}

// python/plots/common.py: missing file, missing column, bad number and short row each fail with
// exit code 1 and a message naming file, line and column.
TEST(PlotHelpers, FailLoudlyOnMissingOrMalformedCsv) {
  const std::string script = std::string(IMPLICIT_SOURCE_DIR) + "/tests/apps/plots_common_check.py";
  const std::string plots = std::string(IMPLICIT_SOURCE_DIR) + "/python/plots";
  TempDir dir("plots_common");
  const auto r =
      run_shell("/usr/bin/python3 '" + script + "' '" + plots + "' '" + dir.path().string() + "'");
  EXPECT_EQ(r.code, 0) << r.out << r.err;
}

// Every figure drawn from small data reads right, checked through matplotlib's API
// (tests/apps/plots_figures_check.py): each log axis has at least two labelled ticks, no two texts
// overlap, Figure 8's Car Park configs have their own markers, Figure 9's panels share one
// y-range and name their runs, Figure 10's map is zoomed to the path.
TEST(PlotHelpers, EveryFigureReadsRightOnSmallData) {
  const std::string script =
      std::string(IMPLICIT_SOURCE_DIR) + "/tests/apps/plots_figures_check.py";
  const std::string plots = std::string(IMPLICIT_SOURCE_DIR) + "/python/plots";
  TempDir dir("plots_figures");
  const auto r =
      run_shell("/usr/bin/python3 '" + script + "' '" + plots + "' '" + dir.path().string() + "'");
  EXPECT_EQ(r.code, 0) << r.out << r.err;
}

// Each figure script fails (non-zero exit, names the missing file) on a folder without data.
TEST(PlotHelpers, EveryFigureScriptFailsLoudlyWithoutData) {
  const std::filesystem::path plots =
      std::filesystem::path(IMPLICIT_SOURCE_DIR) / "python" / "plots";
  TempDir dir("plots_empty");
  int scripts = 0;
  for (const auto& entry : std::filesystem::directory_iterator(plots)) {
    const auto name = entry.path().filename().string();
    if (!std::regex_match(name, std::regex(R"(figure\d+\.py)"))) continue;
    ++scripts;
    const auto r =
        run_shell("/usr/bin/python3 '" + entry.path().string() + "' '" + dir.path().string() + "'");
    EXPECT_NE(r.code, 0) << name << " drew something without data";
    EXPECT_TRUE(r.err.find(".csv") != std::string::npos ||
                r.err.find("results.json") != std::string::npos)
        << name << " does not name the missing file: " << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / (name.substr(0, name.size() - 3) + ".png")))
        << name;
  }
  if (scripts == 0) GTEST_SKIP() << "no figure scripts yet";
}

}  // namespace
