// The command line on bad input: flag values (usage error, exit 2, the flag named), data that
// cannot be run or scores nothing (exit 1 naming the file and line, or the empty metric), outputs
// that cannot be written (exit 1). What every subcommand shows:
// every_subcommand_bad_input_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;

std::string write_log(const TempDir& dir, const std::string& text) {
  const auto path = dir.path() / "run.log";
  std::ofstream(path) << text;
  return path.string();
}

// A log SLAM and MCL can run: three landmarks seen (roughly) from a car driving along x.
std::string small_log(bool with_truth) {
  std::string text =
      "landmark 1 5 3\nlandmark 2 10 -3\nlandmark 3 15 3\ninitial 0 0 0 0 0.1 0.1 0.01\n";
  for (int n = 1; n <= 40; ++n) {
    const double t = 0.025 * n;
    text += "control " + std::to_string(t) + " 2 0\n";
    if (n % 8 == 0)
      text += "scan " + std::to_string(t) + " 1\nobs 5 0.5 " + std::to_string(n / 16 + 1) + "\n";
    if (with_truth) text += "truth " + std::to_string(t) + " " + std::to_string(2 * t) + " 0\n";
  }
  return text;
}

TEST(Cli, BareCommandPrintsUsageAndExits2) {
  const auto r = run_cli("");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("Subcommands:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("Exit codes"), std::string::npos) << r.err;
}

TEST(Cli, MclNanFlagIsAUsageError) {
  for (const char* value : {"nan", "NaN", "inf", "-inf"}) {
    const auto r = run_cli(std::string("mcl --p ") + value);
    EXPECT_EQ(r.code, 2) << value;
    EXPECT_NE(r.err.find("--p"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("expected a finite number in [0, 10]"), std::string::npos) << r.err;
  }
  EXPECT_EQ(run_cli("slam --control-noise nan").code, 2);
}

TEST(Cli, MclLabelGateOutOfRangeIsAUsageError) {
  for (const char* value : {"x", "nan", "-1", "1e7"}) {
    const auto r = run_cli(std::string("mcl --runs 1 --label-gate ") + value);
    EXPECT_EQ(r.code, 2) << value;
    EXPECT_NE(r.err.find("--label-gate"), std::string::npos) << r.err;
  }
}

// A refusal that every run makes (the same InvalidArgument) is that message, exit code 1, not
// "3 of 3 runs failed"; a failure in some runs keeps the summary with each run's message.
TEST(Cli, ARefusalInEveryRunIsThatMessage) {
  const std::string cli = std::string("'") + IMPLICIT_CLI + "' mcl --runs 3 -M 10";
  const auto all = implicit::test::run_shell("IMPLICIT_FAIL_RUN=-2 " + cli);
  EXPECT_EQ(all.code, 1) << all.err;
  EXPECT_NE(all.err.find("refusal requested by IMPLICIT_FAIL_RUN=-2"), std::string::npos)
      << all.err;
  EXPECT_EQ(all.err.find("runs failed"), std::string::npos) << all.err;
  const auto one = implicit::test::run_shell("IMPLICIT_FAIL_RUN=1 " + cli);
  EXPECT_NE(one.code, 0);
  EXPECT_NE(one.err.find("1 of 3 runs failed"), std::string::npos) << one.err;
  EXPECT_NE(one.err.find("run 1: failure requested"), std::string::npos) << one.err;
}

TEST(Cli, NegativeSeedIsAUsageErrorNotAWrap) {
  const auto r = run_cli("slit --seed -1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--seed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("expected an integer in [0, 2^64 - 1], got '-1'"), std::string::npos)
      << r.err;
  EXPECT_EQ(run_cli("slit --seed 18446744073709551616").code, 2);  // 2^64
}

TEST(Cli, FractionalValueOfAnIntegerFlagSaysInteger) {
  const auto r = run_cli("slam --particles 3.7");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--particles"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("expected an integer in [1, 1000000], got '3.7'"), std::string::npos)
      << r.err;
  const auto range = run_cli("slam --particles 0");
  EXPECT_EQ(range.code, 2);
  EXPECT_NE(range.err.find("expected [1, 1000000], got 0"), std::string::npos) << range.err;
}

TEST(Cli, SlamLogWithNoControlsExits1NamingTheLine) {
  TempDir dir("slam_no_controls");
  const auto log = write_log(dir, "initial 1 0 0 0 0 0 0\nscan 0.5 0\n");
  for (const char* cmd : {"slam --datasets 1 --quiet --data ", "mcl --runs 1 --quiet --data "}) {
    const auto r = run_cli(cmd + log);
    EXPECT_EQ(r.code, 1) << cmd << r.err;
    EXPECT_NE(r.err.find(log + ":1: expected 'control' records"), std::string::npos)
        << cmd << r.err;
  }
}

TEST(Cli, SlamVehicleNanExits1NamingTheLine) {
  TempDir dir("slam_vehicle_nan");
  const auto log = write_log(dir, "# vehicle a=nan\n" + small_log(true));
  const auto r = run_cli("slam --datasets 1 --quiet --data " + log);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find(log + ":1: vehicle comment: field 'a'"), std::string::npos) << r.err;
}

// The `vehicle` record is range-checked like the `# vehicle` comment, in mcl and slam alike.
TEST(Cli, VehicleRecordOutOfRangeExits1NamingKeyValueAndLine) {
  TempDir dir("vehicle_record_range");
  for (const std::string kv : {"a=1e300", "a=150", "L=1e300", "dt=100"}) {
    const auto log = write_log(dir, "vehicle ute " + kv + "\n" + small_log(true));
    const std::string key = kv.substr(0, kv.find('=')), value = kv.substr(kv.find('=') + 1);
    for (const char* cmd : {"mcl --runs 1 --quiet --data ", "slam --datasets 1 --quiet --data "}) {
      const auto r = run_cli(cmd + log);
      EXPECT_EQ(r.code, 1) << cmd << kv << "\n" << r.err;
      EXPECT_NE(r.err.find(log + ":1: field '" + key + "': expected "), std::string::npos)
          << cmd << kv << "\n"
          << r.err;
      EXPECT_NE(r.err.find(", got '" + value + "'"), std::string::npos) << cmd << r.err;
    }
  }
}

TEST(Cli, VehicleRecordWithAnUnknownKeyExits1InMclAndSlam) {
  TempDir dir("vehicle_record_key");
  const auto log = write_log(dir, "vehicle unicycle dt=0.025 foo=3\n" + small_log(true));
  for (const char* cmd : {"mcl --runs 1 --quiet --data ", "slam --datasets 1 --quiet --data "}) {
    const auto r = run_cli(cmd + log);
    EXPECT_EQ(r.code, 1) << cmd << r.err;
    EXPECT_NE(r.err.find("vehicle 'unicycle': expected parameters among dt, got 'foo'"),
              std::string::npos)
        << cmd << r.err;
  }
}

// A log without a `vehicle` record runs as the Car Park's Ute: said on stderr even with --json,
// and recorded in the JSON; a log that declares its vehicle says nothing of the kind.
TEST(Cli, LogWithoutAVehicleRecordSaysTheUteIsAssumed) {
  TempDir dir("vehicle_assumed");
  const auto bare = write_log(dir, small_log(true));
  for (const char* cmd :
       {"mcl --runs 1 --json --data ", "slam --method ekf --datasets 1 --json --data "}) {
    const auto r = run_cli(cmd + bare);
    ASSERT_EQ(r.code, 0) << cmd << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["vehicle_assumed"], true) << cmd << r.out;
    EXPECT_NE(r.err.find("warning: the log '"), std::string::npos) << cmd << r.err;
    EXPECT_NE(r.err.find("declares no vehicle (no 'vehicle' record): it runs as the ute with "
                         "dt=0.025 L=2.83 H=0.76 a=3.78 b=0.5, the Car Park's car"),
              std::string::npos)
        << cmd << r.err;
  }
  const auto declared =
      write_log(dir, "vehicle ute dt=0.025 L=2.83 H=0.76 a=3.78 b=0.5\n" + small_log(true));
  for (const char* cmd :
       {"mcl --runs 1 --json --data ", "slam --method ekf --datasets 1 --json --data "}) {
    const auto r = run_cli(cmd + declared);
    ASSERT_EQ(r.code, 0) << cmd << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["vehicle_assumed"], false) << cmd << r.out;
    EXPECT_EQ(r.err.find("declares no vehicle"), std::string::npos) << cmd << r.err;
  }
}

TEST(Cli, SlamRunThatScoresNothingExits1UnlessAllowed) {
  TempDir dir("slam_unscored");
  const auto log = write_log(dir, small_log(false));
  const std::string args = "slam --method ekf --association known --datasets 1 --json --data ";
  const auto r = run_cli(args + log);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("scored nothing: error_percent_mean is not a finite number"),
            std::string::npos)
      << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["error_percent_mean"].is_null()) << r.out;
  EXPECT_EQ(j["scored_steps_min"], 0) << r.out;
  const auto allowed = run_cli(args + log + " --allow-empty");
  EXPECT_EQ(allowed.code, 0) << allowed.err;
  EXPECT_NE(allowed.err.find("allowed by --allow-empty"), std::string::npos) << allowed.err;
  // The same log with truth (and its vehicle declared, else the assumed Ute is warned about) is
  // scored, and says nothing.
  const auto scored = run_cli(
      args + write_log(dir, "vehicle ute dt=0.025 L=2.83 H=0.76 a=3.78 b=0.5\n" + small_log(true)));
  EXPECT_EQ(scored.code, 0) << scored.err;
  EXPECT_EQ(scored.err.find("warning"), std::string::npos) << scored.err;
}

// mcl on a log without truth scores nothing: exit 1 with the metrics null, exit 0 with
// --allow-empty (as docs/cli.md says); every run used to fail instead.
TEST(Cli, MclRunThatScoresNothingExits1UnlessAllowed) {
  TempDir dir("mcl_unscored");
  const auto log = write_log(dir, small_log(false));
  const std::string args = "mcl --runs 1 -M 20 --json --data " + log;
  const auto r = run_cli(args);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("scored nothing: error_percent_mean is not a finite number"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["error_percent_mean"].is_null()) << r.out;
  const auto allowed = run_cli(args + " --allow-empty");
  EXPECT_EQ(allowed.code, 0) << allowed.err;
  EXPECT_TRUE(nlohmann::json::parse(allowed.out)["rmse_m"].is_null()) << allowed.out;
  EXPECT_NE(allowed.err.find("allowed by --allow-empty"), std::string::npos) << allowed.err;
}

// A kidnapping that never happens (or leaves nothing after its gap), and a global start on a log
// without truth, reported a rate of 0 for a test that was never made: now an error naming the
// flag and why, unless --allow-empty, with which the JSON says what was empty.
TEST(Cli, MclGlobalOrKidnapTestThatCannotHappenExits1UnlessAllowed) {
  TempDir dir("mcl_empty_tests");
  const auto sim =
      run_cli("simulate --model ute --seed 3 --quiet --out " + (dir.path() / "sim.log").string());
  ASSERT_EQ(sim.code, 0) << sim.err;
  std::ifstream in(dir.path() / "sim.log");
  std::string text, line;
  while (std::getline(in, line))
    if (!line.starts_with("truth ")) text += line + "\n";
  const auto no_truth = write_log(dir, text);
  struct Case {
    std::string args, message, rate;
  };
  const std::vector<Case> cases = {
      {"--duration 30 --kidnap-at 100", "mcl --kidnap-at 100: expected a time before the log's end",
       "kidnap_recovery_rate"},
      {"--duration 30 --kidnap-at 20 --kidnap-skip 20",
       "mcl --kidnap-at 20 --kidnap-skip 20: expected steps after the gap", "kidnap_recovery_rate"},
      {"--duration 20 --init global --data " + no_truth,
       "mcl --init global: expected ground truth ('truth' records) in the log to score the runs, "
       "got none",
       "global_success_rate"}};
  for (const auto& c : cases) {
    const std::string args = "mcl --runs 1 -M 50 --json " + c.args;
    const auto r = run_cli(args);
    EXPECT_EQ(r.code, 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("--allow-empty runs it anyway"), std::string::npos) << r.err;
    const auto allowed = run_cli(args + " --allow-empty");
    ASSERT_EQ(allowed.code, 0) << args << "\n" << allowed.err;
    const auto j = nlohmann::json::parse(allowed.out);
    EXPECT_NE(j["empty"].get<std::string>().find(c.message), std::string::npos) << allowed.out;
    EXPECT_TRUE(j[c.rate].is_null()) << allowed.out;
  }
}

TEST(Cli, SlamOutIntoUnwritableFolderExits1) {
  // procfs refuses new files even to root, for whom a chmod 555 folder is still writable.
  const auto r = run_cli("slam --method ekf --datasets 1 --quiet --out /proc/self");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("/proc/self/slam_ekf_M1_path.csv: expected a writable output file"),
            std::string::npos)
      << r.err;
}

TEST(Cli, ReportOnlyWithAnEmptyObjectExits1NamingTheFile) {
  TempDir dir("report_only_empty");
  std::ofstream(dir.path() / "results.json") << "{}\n";
  const auto r =
      run_cli("reproduce --report-only --no-figures --quiet --out " + dir.path().string());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find((dir.path() / "results.json").string() +
                       ": expected the results.json of `implicit reproduce`"),
            std::string::npos)
      << r.err;
}

TEST(Cli, ReportOnlyWithWronglyTypedJsonNamesTheFile) {
  TempDir dir("report_only_typed");
  std::ofstream(dir.path() / "results.json")
      << R"({"schema": "implicit-reproduce-1", "experiments": {"slit": 5}, "seed": "x"})";
  const auto r =
      run_cli("reproduce --report-only --no-figures --quiet --out " + dir.path().string());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find((dir.path() / "results.json").string() + ": "), std::string::npos) << r.err;
}

TEST(Cli, ReportOnlyWithANumberBeyondADoubleNamesTheFile) {
  TempDir dir("report_only_1e999");
  std::ofstream(dir.path() / "results.json")
      << R"({"schema": "implicit-reproduce-1", "experiments": {}, "seconds_total": 1e999})";
  const auto r =
      run_cli("reproduce --report-only --no-figures --quiet --out " + dir.path().string());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find((dir.path() / "results.json").string() + ": "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("out_of_range"), std::string::npos) << r.err;
}

// A count the report reads as an int, written as a huge double: converting it was undefined
// behaviour (found by fuzz_results_json under UBSan); now a range error naming where it is.
TEST(Cli, ReportOnlyWithACountOutOfRangeNamesItsPlace) {
  TempDir dir("report_only_huge_count");
  std::ofstream(dir.path() / "results.json")
      << R"({"schema": "implicit-reproduce-1", "experiments": {"slit": [{"settings": )"
      << R"({"runs": 7.8e100}}]}})";
  const auto r =
      run_cli("reproduce --report-only --no-figures --quiet --out " + dir.path().string());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find((dir.path() / "results.json").string() +
                       ": the number at /experiments/slit/0/settings/runs is 7.8e+100, out of "
                       "range (|x| < 2^31)"),
            std::string::npos)
      << r.err;
}

// A results.json nested 20 000 levels deep overflowed the stack in the recursive range check;
// the parser now refuses nesting beyond 64 levels, naming the file and the level.
TEST(Cli, ReportOnlyWithJsonNestedTooDeepNamesTheFileAndTheLevel) {
  TempDir dir("report_only_deep");
  std::ofstream(dir.path() / "results.json")
      << R"({"schema": "implicit-reproduce-1", "experiments": {"slit": )" << std::string(20000, '[')
      << std::string(20000, ']') << "}}";
  const auto r =
      run_cli("reproduce --report-only --no-figures --quiet --out " + dir.path().string());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find((dir.path() / "results.json").string() +
                       ": expected JSON nested at most 64 levels deep, got an array or object at "
                       "level 65"),
            std::string::npos)
      << r.err;
}

// slit, arm and himmelblau write their CSVs like mcl and slam: under temporary names renamed
// only when complete, so an unwritable folder is an error (exit 1) naming the file.
TEST(Cli, ControlCommandsOutIntoUnwritableFolderExit1) {
  for (const std::string command : {"slit --runs 2 --naive-small 5 --naive-large 5",
                                    "arm --estimator closed-form", "himmelblau --runs 2 -M 10"}) {
    const auto r = run_cli(command + " --quiet --out /proc/self");
    EXPECT_EQ(r.code, 1) << command << "\n" << r.err;
    EXPECT_NE(r.err.find("expected a writable output file"), std::string::npos) << command << "\n"
                                                                                << r.err;
  }
}

// Every subcommand that writes files into --out: a folder that cannot be created (procfs refuses
// new folders even to root), a file in its place, or a folder that refuses files is an error
// (exit 1) naming --out and the path, not a raw filesystem error.
TEST(Cli, EveryOutputErrorNamesOutAndThePath) {
  TempDir dir("out_is_a_file");
  const std::string file = (dir.path() / "a_file").string();
  std::ofstream(file) << "x\n";
  const std::vector<std::pair<std::string, std::string>> outs = {
      {"/proc/implicit/none", "--out /proc/implicit/none: expected a folder that can be created"},
      {file, "--out " + file + ": expected a folder for the output files, got a file"},
      {"/proc/self", "--out: /proc/self/"}};
  for (const std::string command :
       {"arm --estimator closed-form", "himmelblau --runs 2 -M 10",
        "slit --runs 2 --naive-small 5 --naive-large 5", "mcl --runs 1 -M 20",
        "mcl --init global --runs 1 -M 20 --duration 50", "slam --method ekf --datasets 1",
        "proposal-gain --runs 1 --duration 10", "reproduce --quick --only arm --no-figures"})
    for (const auto& [out, expected] : outs) {
      const auto r = run_cli(command + " --quiet --out " + out);
      EXPECT_EQ(r.code, 1) << command << " --out " << out << "\n" << r.err;
      EXPECT_NE(r.err.find(expected), std::string::npos) << command << " --out " << out << "\n"
                                                         << r.err;
    }
  // simulate's --out is the log file itself.
  const auto r = run_cli("simulate --quiet --out /proc/implicit/none.log");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("--out: /proc/implicit/none.log: expected a writable output file, got a "
                       "folder where none.log.tmp"),
            std::string::npos)
      << r.err;
}

TEST(Cli, ControlCommandsLeaveOnlyCompleteFiles) {
  TempDir dir("control_outputs");
  const auto r =
      run_cli("slit --runs 3 --naive-small 5 --naive-large 5 --quiet --out " + dir.path().string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  // .resume/ holds the finished runs' records for --resume (docs/cluster.md), on purpose.
  const std::vector<std::string> expected = {".resume", "figure1_guided.csv",
                                             "figure1_unguided.csv", "figure2_slit.csv",
                                             "slit_runs_corrected_M50.csv"};
  EXPECT_EQ(names, expected);
  std::ifstream runs(dir.path() / "slit_runs_corrected_M50.csv");
  std::string line;
  int lines = 0;
  while (std::getline(runs, line)) ++lines;
  EXPECT_EQ(lines, 1 + 3);  // header and one row per run
}

TEST(Cli, SigtermStopsWithAMessageAndLeavesNoPartialOutput) {
  TempDir dir("sigterm");
  const auto r = implicit::test::run_shell(
      std::string("{ '") + IMPLICIT_CLI +
      "' slam --method fastslam2 --datasets 100000 --quiet --out '" + dir.path().string() +
      "' & pid=$!; sleep 2; kill -TERM $pid; wait $pid; }");
  EXPECT_EQ(r.code, 128 + 15) << r.err;
  EXPECT_NE(r.err.find("implicit: stopped by SIGTERM; 0 output file(s) were complete and are kept"),
            std::string::npos)
      << r.err;
  // The runs that finished are kept in .resume/ on purpose (`--resume` continues from them);
  // nothing else may be left.
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    if (entry.path().filename() != ".resume") ADD_FAILURE() << "left behind: " << entry.path();
}

// ---- map and simulate --map: every flag, the files they name -------------------------------

// A 4 m x 4 m room of 0.1 m cells walled by its border, with a pillar at x, y in [1.8, 2.2);
// `pixels` cuts the image short (a PGM that does not match its header and the YAML).
void write_laser_map(const std::filesystem::path& yaml, const std::string& image, int pixels) {
  std::string pgm = "P2\n40 40\n255\n";
  for (int k = 0; k < pixels; ++k) {
    const int ix = k % 40, iy = k / 40;
    const bool wall =
        ix == 0 || iy == 0 || ix == 39 || iy == 39 || (ix >= 18 && ix < 22 && iy >= 18 && iy < 22);
    pgm += wall ? "0\n" : "254\n";
  }
  std::ofstream(yaml.parent_path() / image) << pgm;
  std::ofstream(yaml) << "image: " << image << "\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\n"
                      << "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
}

struct BadInput {
  std::string args;  ///< MAP, LOG, DIR are replaced by the fixture's paths
  int code;
  std::vector<std::string> says;  ///< each must appear in stderr
};

TEST(Cli, MapAndLaserSimulationRefuseBadInputNamingTheFlagOrFile) {
  TempDir dir("laser_bad_input");
  const std::string d = dir.path().string();
  write_laser_map(dir.path() / "room.yaml", "room.pgm", 40 * 40);
  write_laser_map(dir.path() / "short.yaml", "short.pgm", 40 * 40 - 7);
  std::filesystem::create_directories(dir.path() / "a b");
  write_laser_map(dir.path() / "a b" / "room.yaml", "room.pgm", 40 * 40);
  std::string carmen;
  for (int k = 0; k < 3; ++k) {
    carmen += "FLASER 4";
    for (int i = 0; i < 4; ++i) carmen += " 1.5";
    carmen += " 2 2 0 2 2 0 " + std::to_string(k) + " host " + std::to_string(k) + "\n";
  }
  std::ofstream(dir.path() / "room.log") << carmen;
  std::ofstream(dir.path() / "robot.txt") << "landmark 1 5 3\ncontrol 0.1 2 0\n";
  const std::string sim = "simulate --map MAP --out DIR/s.log";
  const std::vector<BadInput> rows = {
      {"map --out DIR/m.yaml", 2, {"--data is required"}},
      {"map --data LOG", 2, {"--out is required"}},
      {"map --data LOG --out DIR/m.txt", 2, {"--out: expected a YAML file name ending in .yaml"}},
      {"map --data LOG --out /proc/self/m.yaml", 1, {"map --out", "/proc/self/m.pgm"}},
      {"map --data DIR/none.log --out DIR/m.yaml", 1, {"map --data", "none.log"}},
      {"map --data DIR/robot.txt --out DIR/m.yaml", 1, {"map --data", "robot.txt:1", "CARMEN"}},
      {"map --data DIR/short.pgm --out DIR/m.yaml",
       1,
       {"map --data", "short.pgm", "at least one laser scan"}},
      {"map --data LOG --out DIR/m.yaml --resolution nan", 2, {"--resolution", "finite"}},
      {"map --data LOG --out DIR/m.yaml --resolution x", 2, {"--resolution", "got 'x'"}},
      {"map --data LOG --out DIR/m.yaml --resolution -0.1", 2, {"--resolution", "got -0.1"}},
      {"map --data LOG --out DIR/m.yaml --resolution 2", 2, {"--resolution", "[0.005, 1]"}},
      {"map --data LOG --out DIR/m.yaml --max-range nan", 2, {"--max-range", "finite"}},
      {"map --data LOG --out DIR/m.yaml --max-range -1", 2, {"--max-range", "got -1"}},
      {"map --data LOG --out DIR/m.yaml --max-range 1e9", 2, {"--max-range", "[0, 1000]"}},
      {"map --data LOG --out DIR/m.yaml --min-echoes -1", 2, {"--min-echoes", "got -1"}},
      {"map --data LOG --out DIR/m.yaml --min-echoes 256", 2, {"--min-echoes", "[0, 255]"}},
      {"map --data LOG --out DIR/m.yaml --min-echoes 1.5", 2, {"--min-echoes"}},
      {"simulate --map DIR/none.yaml --out DIR/s.log", 1, {"simulate --map", "none.yaml"}},
      {"simulate --map DIR/short.yaml --out DIR/s.log", 1, {"simulate --map", "short.pgm"}},
      {"simulate --map MAP", 2, {"--out is required"}},
      {"simulate --out DIR/s.log --waypoints '1,1;3,1'", 2, {"--waypoints requires --map"}},
      {"simulate --out DIR/s.log --beams 180", 2, {"--beams requires --map"}},
      {sim + " --steps 10", 2, {"--steps excludes --map"}},
      {sim + " --model ute", 2, {"--model excludes --map"}},
      {sim + " --waypoints 1,1", 2, {"--waypoints", "at least 2 points"}},
      {sim + " --waypoints 'a,b;1,1'", 2, {"--waypoints", "got 'a,b' as point 1"}},
      {sim + " --waypoints '1,1;nan,2'", 2, {"--waypoints", "got 'nan,2' as point 2"}},
      {sim + " --waypoints '1;2'", 2, {"--waypoints", "got '1' as point 1"}},
      {sim + " --waypoints '0.05,0.05;1,1'", 1, {"--waypoints", "point 1", "room.yaml"}},
      {sim + " --waypoints '1,2;3,2'", 1, {"--waypoints", "segment from point 1", "blocked"}},
      {sim + " --waypoints '1,2;1,1;3,1;3,2' --laps 2", 1, {"--waypoints", "way back", "--laps"}},
      {sim + " --waypoints '1,1;1,1'", 1, {"--waypoints", "span a path"}},
      {sim + " --clearance 3", 1, {"--clearance", "room.yaml"}},
      {sim + " --scan-period 0.001 --laps 1000 --beams 10000", 1, {"readings", "--scan-period"}},
      {"simulate --map MAP --out /proc/self/s.log", 1, {"/proc/self/s.log: expected a writable"}},
      {"simulate --map MAP --out /proc/self/s.log.gz", 1, {"/proc/self/s.log.gz: expected a"}},
      {sim + " --format xml", 2, {"--format", "xml"}},
      {"simulate --out DIR/s.log --format robot-log", 2, {"--format requires --map"}},
      {"simulate --out DIR/s.log --odometry-alphas 0 0 0 0", 2, {"--odometry-alphas requires"}},
      {sim + " --odometry-alphas 0.1 0.1 0.1 0.1", 1, {"--odometry-alphas", "--format robot-log"}},
      {sim + " --format robot-log --odometry-alphas 0.1 0.1 0.1", 2, {"--odometry-alphas"}},
      {sim + " --format robot-log --odometry-alphas 0.1 nan 0.1 0.1",
       2,
       {"--odometry-alphas", "finite"}},
      {sim + " --format robot-log --odometry-alphas 0.1 11 0.1 0.1",
       2,
       {"--odometry-alphas", "[0, 10]"}},
      {"simulate --map 'DIR/a b/room.yaml' --format robot-log --out DIR/s.txt",
       1,
       {"'a b/room.yaml'", "without blanks"}},
  };
  // Numeric flags: not a number, NaN, below and above the accepted range.
  const std::vector<std::pair<std::string, std::vector<std::string>>> numeric = {
      {"--speed", {"x", "nan", "0", "11"}},        {"--turn-rate", {"x", "inf", "0", "721"}},
      {"--scan-period", {"x", "nan", "-1", "61"}}, {"--clearance", {"x", "nan", "-0.1", "11"}},
      {"--laps", {"x", "1.5", "0", "1001"}},       {"--beams", {"x", "3.5", "1", "10001"}},
      {"--fov-deg", {"x", "nan", "0", "181"}},     {"--range-max", {"x", "nan", "0", "60"}},
      {"--range-sd", {"x", "nan", "-1", "101"}},
  };
  std::vector<BadInput> all = rows;
  for (const auto& [flag, values] : numeric)
    for (const auto& v : values) all.push_back({sim + " " + flag + " " + v, 2, {flag, "expected"}});
  for (BadInput row : all) {
    for (const auto& [key, value] : {std::pair<std::string, std::string>{"MAP", d + "/room.yaml"},
                                     {"LOG", d + "/room.log"},
                                     {"DIR", d}}) {
      for (std::size_t at = row.args.find(key); at != std::string::npos;
           at = row.args.find(key, at + value.size()))
        row.args.replace(at, key.size(), value);
    }
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    for (const auto& s : row.says)
      EXPECT_NE(r.err.find(s), std::string::npos) << row.args << "\n" << r.err;
  }
  // Nothing was written by a refused command (the map and log fixtures aside).
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name.rfind("room.", 0) == 0 || name.rfind("short.", 0) == 0 ||
                name == "robot.txt" || name == "a b")
        << "left behind: " << name;
  }
}

// A robot log of a laser run (docs/formats.md, "Laser runs"): each malformed record names the
// file and line, a missing map or stream of records names what is missing, a flag that means
// nothing for it is refused.
TEST(Cli, LaserMclOnARobotLogRefusesBadInputNamingFileAndLine) {
  TempDir dir("laser_robot_log_bad_input");
  write_laser_map(dir.path() / "room.yaml", "room.pgm", 40 * 40);
  // Three scans 0.3 m apart in the 4 m room: enough to run, no truth.
  const std::string good =
      "map room.yaml\nodometry 0 1 1 0\nlaser 0 -1 1 0 5 3 1 1 1\nodometry 1 1.3 1 0\n"
      "laser 1 -1 1 0 5 3 1 1 1\nodometry 2 1.6 1 0\nlaser 2 -1 1 0 5 3 1 1 1\n";
  const std::vector<std::pair<std::string, std::string>> logs = {
      {"good.txt", good},
      {"offmap.txt", good + "truth 0 50 50 0\n"},
      {"nomap.txt", "odometry 0 0 0 0\nlaser 0 -1 1 0 5 3 1 1 1\n"},
      {"missing.txt", "# a laser run\nmap gone.yaml\nodometry 0 0 0 0\n"},
      {"nan.txt", "map room.yaml\nodometry 0 0 0 0\nlaser 0 -1 1 0 5 3 1 nan 1\n"},
      {"count.txt", "laser 0 -1 1 0 5 3 1 1\n"},
      {"flat.txt", "laser 0 -1 0 0 5 1 1\n"},
      {"time.txt", "odometry 1 0 0 0\nodometry 1 0 0 0\n"},
      {"twomaps.txt", "map room.yaml\nmap room.yaml\n"},
      {"noodom.txt", "map room.yaml\nlaser 0 -1 1 0 5 3 1 1 1\n"},
      {"nolaser.txt", "map room.yaml\nodometry 0 0 0 0\n"},
      {"late.txt", "map room.yaml\nodometry 5 0 0 0\nodometry 6 0 0 0\nlaser 0 -1 1 0 5 1 1\n"},
  };
  for (const auto& [name, text] : logs) std::ofstream(dir.path() / name) << text;
  const std::string d = dir.path().string() + "/";
  const std::string mcl = "mcl --sensor laser -M 20 --runs 1 --json --data " + d;
  const std::vector<BadInput> rows = {
      {mcl + "nomap.txt", 1, {"nomap.txt", "--map FILE, or a 'map' record", "got neither"}},
      {mcl + "missing.txt", 1, {"missing.txt:2: field 'file'", "got 'gone.yaml'"}},
      {mcl + "nan.txt", 1, {"nan.txt:3: field 'r_2'", "got 'nan'"}},
      {mcl + "count.txt", 1, {"count.txt:1: field 'n': expected 3 readings after it, got 2"}},
      {mcl + "flat.txt", 1, {"flat.txt:1: field 'angle_increment'"}},
      {mcl + "time.txt", 1, {"time.txt:2: field 'time'", "'odometry'"}},
      {mcl + "twomaps.txt", 1, {"twomaps.txt:2: expected one 'map' record"}},
      {mcl + "noodom.txt", 1, {"noodom.txt", "expected 'odometry' records"}},
      {mcl + "nolaser.txt", 1, {"nolaser.txt", "expected 'laser' records"}},
      {mcl + "late.txt", 1, {"late.txt", "time span of the 'odometry' records (5 to 6 s)"}},
      {mcl + "offmap.txt", 1, {"offmap.txt", "outside the map"}},
      {mcl + "good.txt --map " + d + "none.yaml", 1, {"none.yaml"}},
      {mcl + "good.txt --init global --alphas 0.1 0.1 0.1 0.1",
       1,
       {"--alphas", "good.txt records its odometry", "--filter-alphas"}},
      {mcl + "good.txt", 1, {"known start", "no truth", "--init global"}},
  };
  for (const BadInput& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    for (const auto& s : row.says)
      EXPECT_NE(r.err.find(s), std::string::npos) << row.args << "\n" << r.err;
  }
}

}  // namespace
