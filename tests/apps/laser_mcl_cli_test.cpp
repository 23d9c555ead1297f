// `implicit mcl --sensor laser`: a short run on the bundled ACES log gives the documented JSON,
// the same numbers for any thread count and a TUM trajectory; and every laser flag's bad values,
// bad files and models that do not fit are refused with the exit code and a message naming them.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

const std::string kAces = std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz";

std::string laser(const std::string& args) {
  return "mcl --sensor laser --quiet --runs 1 -M 20 --max-updates 12 --data " + kAces + " " + args;
}

TEST(LaserMclCli, ShortRunGivesTheDocumentedJsonForAnyThreadCount) {
  TempDir dir("laser_mcl_json");
  const std::string tum = (dir.path() / "estimate.tum").string();
  const auto one = run_cli(laser("--json --threads 1 --trajectory " + tum));
  ASSERT_EQ(one.code, 0) << one.err;
  const auto j = nlohmann::json::parse(one.out);
  for (const char* key : {"experiment",
                          "data",
                          "proposal",
                          "implicit_starts",
                          "implicit_start_probe",
                          "implicit_defensive",
                          "particles",
                          "runs",
                          "updates",
                          "map",
                          "odometry_noise",
                          "filter_alphas",
                          "laser",
                          "position_rmse_m",
                          "heading_rmse_rad",
                          "cpu_us_per_update",
                          "ess_fraction",
                          "lost_runs",
                          "per_run",
                          "version",
                          "commit"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["experiment"], "laser_mcl");
  EXPECT_EQ(j["proposal"], "implicit");
  EXPECT_EQ(j["updates"], 12);
  EXPECT_TRUE(j["map"]["built_from_reference"].get<bool>());
  const double rmse = j["position_rmse_m"]["mean"].get<double>();
  EXPECT_TRUE(std::isfinite(rmse) && rmse > 0.0) << rmse;
  const auto two = run_cli(laser("--json --threads 2"));
  ASSERT_EQ(two.code, 0) << two.err;
  const auto k = nlohmann::json::parse(two.out);
  EXPECT_EQ(j["position_rmse_m"], k["position_rmse_m"]);  // bit-identical, not merely close
  EXPECT_EQ(j["per_run"][0]["final_error_m"], k["per_run"][0]["final_error_m"]);
  // The trajectory: one TUM line (t x y z qx qy qz qw) per update.
  std::ifstream in(tum);
  std::string line;
  int lines = 0;
  while (std::getline(in, line)) {
    if (line.starts_with('#')) continue;  // the header comment
    std::istringstream fields(line);
    double v[8];
    for (double& x : v) ASSERT_TRUE(fields >> x) << line;
    EXPECT_NEAR(v[6] * v[6] + v[7] * v[7], 1.0, 1e-8) << line;  // a unit quaternion about z
    ++lines;
  }
  EXPECT_EQ(lines, 12);
}

struct BadRow {
  std::string args;
  int code;
  std::string says;  ///< the message names the flag or the file
};

TEST(LaserMclCli, BadFlagValuesAreUsageErrorsNamingTheFlag) {
  const std::vector<BadRow> rows = {
      {"--sensor sonar", 2, "--sensor"},
      {"--alphas 0.1 0.1 0.1", 2, "--alphas"},
      {"--alphas nan 0 0 0", 2, "--alphas"},
      {"--alphas -1 0 0 0", 2, "--alphas"},
      {"--filter-alphas 0 0 0 inf", 2, "--filter-alphas"},
      {"--z-hit 0", 2, "--z-hit"},
      {"--z-rand -1", 2, "--z-rand"},
      {"--sigma-hit nan", 2, "--sigma-hit"},
      {"--max-beams 0", 2, "--max-beams"},
      {"--max-beams 2.5", 2, "--max-beams"},
      {"--laser-max-dist 0", 2, "--laser-max-dist"},
      {"--laser-max-range nan", 2, "--laser-max-range"},
      {"--interpolation cubic", 2, "--interpolation"},
      {"--aggregation sum", 2, "--aggregation"},
      {"--update-min-d -1", 2, "--update-min-d"},
      {"--update-min-a nan", 2, "--update-min-a"},
      {"--map-resolution 0", 2, "--map-resolution"},
      {"--map-min-echoes -1", 2, "--map-min-echoes"},
      {"--map-min-echoes 256", 2, "--map-min-echoes"},
      {"--map-min-echoes two", 2, "--map-min-echoes"},
      {"--max-updates -3", 2, "--max-updates"},
      {"--global-updates 0", 2, "--global-updates"},
      {"--global-radius 0", 2, "--global-radius"},
      {"--starts 0", 2, "--starts"},
      {"--starts 65", 2, "--starts"},
      {"--starts 1.5", 2, "--starts"},
      {"--start-probe -1", 2, "--start-probe"},
      {"--start-probe 21", 2, "--start-probe"},
      {"--start-probe 2.5", 2, "--start-probe"},
      {"--defensive -0.1", 2, "--defensive"},
      {"--defensive 1", 2, "--defensive"},
      {"--defensive nan", 2, "--defensive"},
      {"--laser-model sonar", 2, "--laser-model"},
      {"--z-short -1", 2, "--z-short"},
      {"--z-max nan", 2, "--z-max"},
      {"--lambda-short 0", 2, "--lambda-short"},
      {"--kld-err 0", 2, "--kld-err"},
      {"--recovery sometimes", 2, "--recovery"},
  };
  for (const BadRow& row : rows) {
    const auto r = run_cli(laser(row.args));
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.says), std::string::npos) << row.args << "\n" << r.err;
  }
}

TEST(LaserMclCli, FilesAndModelsThatDoNotFitExit1NamingThem) {
  TempDir dir("laser_mcl_bad");
  const auto not_carmen = dir.path() / "robot.log";
  std::ofstream(not_carmen) << "landmark 1 5 3\ninitial 0 0 0 0 0.1 0.1 0.01\ncontrol 0.1 1 0\n";
  // A valid map far away from the log's poses: 10 x 10 free cells at (1000, 1000).
  std::ofstream(dir.path() / "far.pgm", std::ios::binary)
      << "P5\n10 10\n255\n"
      << std::string(100, static_cast<char>(254));
  std::ofstream(dir.path() / "far.yaml") << "image: far.pgm\nresolution: 0.5\norigin: [1000.0, "
                                            "1000.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
                                            "free_thresh: 0.196\n";
  const std::string base = "mcl --sensor laser --quiet --runs 1 -M 20 ";
  const std::vector<BadRow> rows = {
      {base, 1, "--data"},
      {base + "--data " + (dir.path() / "missing.log.gz").string(), 1, "missing.log.gz"},
      {base + "--data " + not_carmen.string(), 1, "robot.log"},
      {laser("--map " + (dir.path() / "none.yaml").string()), 1, "none.yaml"},
      {laser("--map " + (dir.path() / "far.yaml").string()), 1, "outside the map"},
      {laser("--aggregation cubed-sum"), 1, "derivatives"},
      {laser("--interpolation nearest"), 1, "nearest"},
      {laser("--defensive 0.1 --implicit-map random"), 1, "defensive share needs the linear map"},
      {laser("--init global --global-updates 20"), 1, "global start needs more than 20"},
      {laser("--trajectory /proc/no/such/estimate.tum"), 2, "estimate.tum"},  // before any run
      {laser("--laser-model beam"), 1, "the beam model has none"},
      {laser("--recovery mixture"), 1, "--recovery mixture"},
      {laser("--kidnap-at 5"), 1, "--kidnap-at"},
  };
  for (const BadRow& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.says), std::string::npos) << row.args << "\n" << r.err;
  }
  // The bootstrap proposal runs nav2's parity settings the implicit one refuses.
  const auto parity =
      run_cli(laser("--method standard --aggregation cubed-sum "
                    "--interpolation nearest --json"));
  EXPECT_EQ(parity.code, 0) << parity.err;
}

TEST(LaserMclCli, BeamModelKldAndRecoveryRunAndSayHowInTheJson) {
  const auto r =
      run_cli(laser("--method standard --laser-model beam --kld --recovery uniform "
                    "--json --threads 1"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["laser_model"], "beam");
  EXPECT_TRUE(j.contains("beam") && !j.contains("laser"));
  EXPECT_EQ(j["beam"]["z_short"], 0.05);
  EXPECT_EQ(j["kld"]["min_particles"], 20);  // the first count bounds KLD-sampling's minimum
  EXPECT_EQ(j["recovery"]["source"], "uniform");
  const double rmse = j["position_rmse_m"]["mean"].get<double>();
  EXPECT_TRUE(std::isfinite(rmse) && rmse > 0.0) << rmse;
  // Without the flags the JSON says there was none.
  const auto plain = run_cli(laser("--json --threads 1"));
  ASSERT_EQ(plain.code, 0) << plain.err;
  const auto k = nlohmann::json::parse(plain.out);
  EXPECT_EQ(k["laser_model"], "likelihood-field");
  EXPECT_TRUE(k["kld"].is_null() && k["recovery"].is_null());
}

}  // namespace

namespace {

// A global start reports how well its first scan fits the reference and the best place it found
// (both log-likelihoods, finite on a log with a reference, the same for any thread count); a
// tracking run has no such keys.
TEST(LaserMclCli, GlobalStartsReportTheFirstScansFit) {
  const std::string global = "mcl --sensor laser --quiet --runs 2 -M 200 --max-updates 12 --data " +
                             kAces + " --init global --global-updates 3 --json";
  const auto one = run_cli(global + " --threads 1");
  ASSERT_EQ(one.code, 0) << one.err;
  const auto two = run_cli(global + " --threads 2");
  ASSERT_EQ(two.code, 0) << two.err;
  const auto j = nlohmann::json::parse(one.out), k = nlohmann::json::parse(two.out);
  ASSERT_EQ(j["per_run"].size(), 2u);
  for (std::size_t r = 0; r < 2; ++r) {
    const auto& run = j["per_run"][r];
    for (const char* key : {"global_success", "updates_to_converge", "first_scan_fit_reference",
                            "first_scan_fit_best"})
      ASSERT_TRUE(run.contains(key)) << key;
    const double ref = run["first_scan_fit_reference"].get<double>();
    const double best = run["first_scan_fit_best"].get<double>();
    EXPECT_TRUE(std::isfinite(ref) && std::isfinite(best)) << ref << " " << best;
    EXPECT_EQ(run["first_scan_fit_reference"], k["per_run"][r]["first_scan_fit_reference"]);
    EXPECT_EQ(run["first_scan_fit_best"], k["per_run"][r]["first_scan_fit_best"]);
  }
  const auto tracking = nlohmann::json::parse(run_cli(laser("--json --threads 1")).out);
  EXPECT_FALSE(tracking["per_run"][0].contains("first_scan_fit_reference"));
  EXPECT_FALSE(tracking["per_run"][0].contains("first_scan_fit_best"));
}

}  // namespace
