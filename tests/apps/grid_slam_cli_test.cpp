// `implicit slam --sensor laser`: grid SLAM on a bundled CARMEN log from the command line. Short
// runs (the first scans of ACES, a few particles) check what the command adds over the library
// (slam/grid tests): the JSON and its statistics over runs, the seeds of the runs, the same bits
// for any thread count, the map and trajectory files, and the refused flag combinations.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

std::string grid_slam_cli_args(const std::string& extra) {
  return "slam --sensor laser --quiet --json --max-scans 40 -M 3 --data " +
         std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz " + extra;
}

TEST(GridSlamCli, TwoRunsGiveTheirSeedsMeanAndStandardError) {
  const auto r = run_cli(grid_slam_cli_args("--method implicit --datasets 2 --seed 5 --threads 1"));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["experiment"], "grid_slam");
  EXPECT_EQ(j["method"], "implicit");
  EXPECT_EQ(j["particles"], 3);
  // Of the first 40 scans, those where the corrected pose moved past the map-update gate.
  const int processed = j["scans_processed"].get<int>();
  EXPECT_GT(processed, 1);
  EXPECT_LE(processed, 40);
  ASSERT_EQ(j["per_run"].size(), 2u);
  EXPECT_EQ(j["per_run"][0]["seed"], 5);
  EXPECT_EQ(j["per_run"][1]["seed"], 6);
  const double a = j["per_run"][0]["relation_translation_m"].get<double>();
  const double b = j["per_run"][1]["relation_translation_m"].get<double>();
  ASSERT_TRUE(std::isfinite(a) && std::isfinite(b));
  EXPECT_GT(a, 0.0);
  EXPECT_NE(a, b) << "two seeds gave the same run";
  // Two runs: the mean is their average, its standard error sd/sqrt(2) = |a - b| / 2.
  EXPECT_DOUBLE_EQ(j["relation_translation_m"]["mean"].get<double>(), 0.5 * (a + b));
  EXPECT_NEAR(j["relation_translation_m"]["se"].get<double>(), 0.5 * std::abs(a - b),
              1e-12 * (a + b));
  for (const char* key : {"odometry_relation_translation_m", "ess_fraction", "real_time_factor",
                          "evaluations_per_particle_and_scan"})
    EXPECT_TRUE(std::isfinite(j[key].get<double>())) << key;
  EXPECT_GT(j["ess_fraction"].get<double>(), 0.0);
  EXPECT_LE(j["ess_fraction"].get<double>(), 1.0);
  // The map score (spec §3.13.5): fractions in [0, 1], the mean and standard error of the runs'.
  EXPECT_EQ(j["map_tolerance_m"].get<double>(), 0.05);  // one cell
  for (const char* key :
       {"map_agreement", "map_occupied_precision", "map_occupied_recall", "map_f1"}) {
    const double ka = j["per_run"][0][key].get<double>(), kb = j["per_run"][1][key].get<double>();
    for (double v : {ka, kb, j[std::string("odometry_") + key].get<double>()}) {
      EXPECT_GE(v, 0.0) << key;
      EXPECT_LE(v, 1.0) << key;
    }
    EXPECT_DOUBLE_EQ(j[key]["mean"].get<double>(), 0.5 * (ka + kb)) << key;
    EXPECT_NEAR(j[key]["se"].get<double>(), 0.5 * std::abs(ka - kb), 1e-12) << key;
  }
  EXPECT_GE(j["map_score_cpu_s"].get<double>(), j["reference_map_cpu_s"].get<double>());
}

TEST(GridSlamCli, OneScanMapsScoreOneInJsonAndText) {
  // On the first scan alone the filter's, the dead-reckoning and the reference map are the same
  // map (scan 0 at the first corrected pose): every fraction is exactly 1.
  const std::string aces = std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz";
  const auto r = run_cli("slam --sensor laser --quiet --json --max-scans 1 -M 2 --data " + aces);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["scans_processed"], 1);
  for (const char* key :
       {"map_agreement", "map_occupied_precision", "map_occupied_recall", "map_f1"}) {
    EXPECT_EQ(j[key]["mean"].get<double>(), 1.0) << key;
    EXPECT_EQ(j[std::string("odometry_") + key].get<double>(), 1.0) << key;
    EXPECT_EQ(j["per_run"][0][key].get<double>(), 1.0) << key;
  }
  const auto t = run_cli("slam --sensor laser --quiet --max-scans 1 -M 2 --data " + aces);
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_NE(t.out.find("map against the reference poses' map: agreement 1.000, occupied precision "
                       "1.000, recall 1.000, F1 1.000 within 0.050 m (odometry alone: 1.000, "
                       "1.000, 1.000, 1.000)"),
            std::string::npos)
      << t.out;
}

TEST(GridSlamCli, SameBitsForAnyThreadCountAndEachProposalRuns) {
  const auto one = run_cli(grid_slam_cli_args("--method implicit --threads 1"));
  const auto two = run_cli(grid_slam_cli_args("--method implicit --threads 2"));
  ASSERT_EQ(one.code, 0) << one.err;
  ASSERT_EQ(two.code, 0) << two.err;
  const auto j1 = nlohmann::json::parse(one.out), j2 = nlohmann::json::parse(two.out);
  EXPECT_EQ(j1["per_run"][0]["relation_translation_m"], j2["per_run"][0]["relation_translation_m"]);
  EXPECT_EQ(j1["per_run"][0]["relation_rotation_deg"], j2["per_run"][0]["relation_rotation_deg"]);
  for (const char* method : {"bootstrap", "gmapping"}) {
    const auto r = run_cli(grid_slam_cli_args(std::string("--threads 1 --method ") + method));
    ASSERT_EQ(r.code, 0) << method << ": " << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["method"], method);
    // Same data seed: the odometry the runs are scored against is the same for every proposal.
    EXPECT_EQ(j["odometry_relation_translation_m"], j1["odometry_relation_translation_m"]);
  }
}

TEST(GridSlamCli, WritesTheMapAndOneTrajectoryPosePerProcessedScan) {
  TempDir dir("grid_slam_cli_files");
  const std::string map = (dir.path() / "aces.yaml").string();
  const std::string est = (dir.path() / "est.tum").string();
  const std::string ref = (dir.path() / "ref.tum").string();
  const auto r = run_cli(grid_slam_cli_args("--method gmapping --threads 1 --map-out " + map +
                                            " --trajectory " + est + " --truth-trajectory " + ref));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(map));
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "aces.pgm"));
  // A map_server pair: the YAML names the image, which is a binary PGM.
  EXPECT_NE(implicit::test::read_file(map).find("image: \"aces.pgm\""), std::string::npos);
  EXPECT_EQ(implicit::test::read_file(dir.path() / "aces.pgm").substr(0, 2), "P5");
  const auto count_rows = [](const std::string& file) {
    std::ifstream in(file);
    int rows = 0;
    for (std::string line; std::getline(in, line);)
      if (!line.empty() && line[0] != '#') ++rows;
    return rows;
  };
  const int processed = nlohmann::json::parse(r.out)["scans_processed"].get<int>();
  EXPECT_EQ(count_rows(est), processed);
  EXPECT_EQ(count_rows(ref), processed);
  // eval scores the two files against each other: one pose per processed scan on both sides.
  const auto e = run_cli("eval --align none --json --ref " + ref + " --est " + est);
  ASSERT_EQ(e.code, 0) << e.err;
  EXPECT_EQ(nlohmann::json::parse(e.out)["ape"]["translation_m"]["count"], processed);
}

TEST(GridSlamCli, FlagsOfTheOtherSensorAndMissingDataAreRefused) {
  const std::string aces = std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz";
  struct Row {
    std::string args;
    int code;
    std::string says;
  };
  const Row rows[] = {
      {"slam --sensor laser --method ekf --data " + aces, 2, "--method"},
      {"slam --sensor laser --method implicit-rb --data " + aces, 2, "implicit-rb"},
      {"slam --sensor laser --method implicit", 2, "--data"},
      {"slam --sensor laser --association ml --data " + aces, 2, "--association"},
      {"slam --sensor laser --range-sd 0.1 --data " + aces, 2, "--range-sd"},
      {"slam --sensor sonar", 2, "--sensor"},
      {"slam --method gmapping", 2, "--sensor laser"},
      {"slam --method bootstrap", 2, "--sensor laser"},
      {"slam --alphas 0.1 0.1 0.1 0.1", 2, "--alphas"},
      {"slam --max-scans 10", 2, "--max-scans"},
      {"slam --g2o /no/such/folder/run.g2o", 2, "/no/such/folder"},  // landmark SLAM writes one too
      {"slam --sensor laser --alphas 0.1 0.1 --data " + aces, 2, "--alphas"},
      {"slam --sensor laser --alphas 0.1 nan 0.1 0.1 --data " + aces, 2, "--alphas"},
      {"slam --sensor laser --max-scans -1 --data " + aces, 2, "--max-scans"},
      {"slam --map-min-echoes 2", 2, "--map-min-echoes"},
      {"slam --sensor laser --map-min-echoes -1 --data " + aces, 2, "--map-min-echoes"},
      {"slam --sensor laser --map-min-echoes 256 --data " + aces, 2, "--map-min-echoes"},
      {"slam --sensor laser --map-min-echoes x --data " + aces, 2, "--map-min-echoes"},
      {"slam --sensor laser --map-out '' --data " + aces, 2, "--map-out"},
      {"slam --sensor laser --data /nonexistent/gone.log.gz", 1, "gone.log.gz"},
  };
  for (const Row& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    EXPECT_NE((r.out + r.err).find(row.says), std::string::npos) << row.args << "\n" << r.err;
  }
}

TEST(GridSlamCli, ALandmarkLogIsRefusedNamingTheFile) {
  TempDir dir("grid_slam_cli_not_laser");
  const std::string file = (dir.path() / "landmarks.log").string();
  std::ofstream(file) << "# implicit-log 1\nvehicle L=2.83 H=0.76 a=3.78 b=0.5\n0 odometry 1 0\n";
  const auto r = run_cli("slam --sensor laser --method implicit --data " + file);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("landmarks.log"), std::string::npos) << r.err;
}

}  // namespace
