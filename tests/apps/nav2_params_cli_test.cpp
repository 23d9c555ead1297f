// `implicit mcl --params`: nav2's AMCL block sets the laser flags of the same meaning. A file and
// the flags it stands for give the same run bit for bit; the command line wins over the file;
// keys without a meaning here are named on stderr; bad files and values are refused naming the
// file, the line and the key.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

std::string nav2_cli_run(const std::string& args) {
  return "mcl --quiet --json --runs 1 --max-updates 8 --threads 1 --method standard --data " +
         std::string(IMPLICIT_SOURCE_DIR) + "/data/carmen/aces-corrected.log.gz " + args;
}

std::string nav2_cli_write(const TempDir& dir, const std::string& name, const std::string& body) {
  const std::string file = (dir.path() / name).string();
  std::ofstream(file) << body;
  return file;
}

TEST(Nav2ParamsCli, AFileGivesTheRunOfTheFlagsItStandsFor) {
  TempDir dir("nav2_params_same");
  const std::string file = nav2_cli_write(dir, "amcl.yaml",
                                          "amcl:\n"
                                          "  ros__parameters:\n"
                                          "    alpha1: 0.03\n"
                                          "    alpha2: 0.01\n"
                                          "    alpha3: 0.04\n"
                                          "    alpha4: 0.02\n"
                                          "    z_hit: 0.8\n"
                                          "    z_rand: 0.2\n"
                                          "    sigma_hit: 0.15\n"
                                          "    max_beams: 40\n"
                                          "    laser_likelihood_max_dist: 1.5\n"
                                          "    update_min_d: 0.3\n"
                                          "    laser_model_type: likelihood_field\n"
                                          "    use_sim_time: true\n");
  const auto by_file = run_cli(nav2_cli_run("-M 40 --params " + file));
  ASSERT_EQ(by_file.code, 0) << by_file.err;
  const auto by_flags =
      run_cli(nav2_cli_run("-M 40 --sensor laser --filter-alphas 0.03 0.01 0.04 0.02 --z-hit 0.8 "
                           "--z-rand 0.2 --sigma-hit 0.15 --max-beams 40 --laser-max-dist 1.5 "
                           "--update-min-d 0.3"));
  ASSERT_EQ(by_flags.code, 0) << by_flags.err;
  const auto a = nlohmann::json::parse(by_file.out), b = nlohmann::json::parse(by_flags.out);
  EXPECT_EQ(a["position_rmse_m"], b["position_rmse_m"]);  // bit for bit
  EXPECT_EQ(a["per_run"][0]["final_error_m"], b["per_run"][0]["final_error_m"]);
  EXPECT_EQ(a["laser"], b["laser"]);
  EXPECT_EQ(a["filter_alphas"], b["filter_alphas"]);
  EXPECT_EQ(a["params"]["used"]["z_hit"], "--z-hit 0.8");
  EXPECT_EQ(a["params"]["not_used"], nlohmann::json::array({"use_sim_time"}));
  EXPECT_NE(by_file.err.find("amcl.yaml:14: use_sim_time is not used"), std::string::npos)
      << by_file.err;
}

TEST(Nav2ParamsCli, TheCommandLineWinsAndTheStockBlockRuns) {
  TempDir dir("nav2_params_stock");
  // nav2's stock amcl block (nav2_bringup's nav2_params.yaml).
  const std::string file = nav2_cli_write(
      dir, "nav2_params.yaml",
      "amcl:\n  ros__parameters:\n    use_sim_time: True\n    alpha1: 0.2\n    alpha2: 0.2\n"
      "    alpha3: 0.2\n    alpha4: 0.2\n    alpha5: 0.2\n    base_frame_id: \"base_footprint\"\n"
      "    beam_skip_distance: 0.5\n    beam_skip_error_threshold: 0.9\n"
      "    beam_skip_threshold: 0.3\n    do_beamskip: false\n    global_frame_id: \"map\"\n"
      "    lambda_short: 0.1\n    laser_likelihood_max_dist: 2.0\n    laser_max_range: 100.0\n"
      "    laser_min_range: -1.0\n    laser_model_type: \"likelihood_field\"\n"
      "    max_beams: 60\n    max_particles: 2000\n    min_particles: 500\n"
      "    odom_frame_id: \"odom\"\n    pf_err: 0.05\n    pf_z: 0.99\n"
      "    recovery_alpha_fast: 0.0\n    recovery_alpha_slow: 0.0\n    resample_interval: 1\n"
      "    robot_model_type: \"nav2_amcl::DifferentialMotionModel\"\n    save_pose_rate: 0.5\n"
      "    sigma_hit: 0.2\n    tf_broadcast: true\n    transform_tolerance: 1.0\n"
      "    update_min_a: 0.2\n    update_min_d: 0.25\n    z_hit: 0.5\n    z_max: 0.05\n"
      "    z_rand: 0.5\n    z_short: 0.05\n    scan_topic: scan\n");
  const auto r = run_cli(nav2_cli_run("-M 30 --z-hit 0.9 --params " + file));
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["laser"]["z_hit"], 0.9);  // the flag, not the file's 0.5
  EXPECT_EQ(j["laser"]["max_beams"], 60);
  EXPECT_EQ(j["particles"], 30);  // -M, not max_particles
  EXPECT_EQ(j["kld"]["min_particles"], 30);
  EXPECT_EQ(j["kld"]["kld_err"], 0.05);
  const auto& overridden = j["params"]["overridden"];
  for (const char* key : {"z_hit", "max_particles"})
    EXPECT_NE(std::find(overridden.begin(), overridden.end(), key), overridden.end()) << key;
  for (const char* key : {"alpha5", "do_beamskip", "resample_interval", "scan_topic"})
    EXPECT_NE(r.err.find(std::string(key) + " is not used"), std::string::npos) << key;
}

TEST(Nav2ParamsCli, BadFilesAndValuesAreRefusedNamingFileLineAndKey) {
  TempDir dir("nav2_params_bad");
  struct Nav2CliBadRow {
    std::string body, args;
    int code;
    std::string says;
  };
  const std::string block = "amcl:\n  ros__parameters:\n";
  const Nav2CliBadRow rows[] = {
      {block + "    z_hit: -1\n", "", 1, "p.yaml:3: z_hit: --z-hit"},
      {block + "    max_beams: many\n", "", 1, "p.yaml:3: max_beams"},
      {block + "    robot_model_type: nav2_amcl::OmniMotionModel\n", "", 1,
       "p.yaml:3: robot_model_type: expected the differential drive"},
      {block + "    laser_model_type: sonar\n", "", 1,
       "laser_model_type: expected likelihood_field"},
      {block + "    laser_min_range: near\n", "", 1, "laser_min_range: expected a number"},
      {"controller_server:\n  ros__parameters:\n    a: 1\n", "", 1, "no 'amcl' block"},
      {"amcl: [\n", "", 1, "p.yaml"},
      {block + "    z_hit: 0.5\n", "--sensor landmark", 1, "--params"},
  };
  const std::string file = (dir.path() / "p.yaml").string();
  for (const auto& row : rows) {
    std::ofstream(file) << row.body;
    const auto r = run_cli(nav2_cli_run(row.args + " --params " + file));
    EXPECT_EQ(r.code, row.code) << row.body;
    EXPECT_NE(r.err.find(row.says), std::string::npos) << row.body << "\n" << r.err;
  }
  const auto gone = run_cli(nav2_cli_run("--params " + (dir.path() / "gone.yaml").string()));
  EXPECT_EQ(gone.code, 2);
  EXPECT_NE(gone.err.find("gone.yaml"), std::string::npos) << gone.err;
}

}  // namespace
