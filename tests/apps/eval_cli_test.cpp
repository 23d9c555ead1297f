// `implicit eval`: APE, RPE and the relation metric from files, as JSON and as a table; every
// flag's bad values (exit 2, the flag named) and every bad file (exit 1, file and line named).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::run_cli;
using implicit::test::TempDir;
using implicit::test::write_file;

/// A square path of 12 poses at 1 Hz, turning at the corners; `shift` moves and `turn` rotates
/// it about z (the estimate is the reference seen in another frame).
std::string eval_cli_square(double shift, double turn, double y_error = 0.0) {
  std::string text = "# t x y z qx qy qz qw\n";
  const double c = std::cos(turn), s = std::sin(turn);
  for (int i = 0; i < 12; ++i) {
    const int side = i / 3, step = i % 3;
    const double x = side == 0 ? step : side == 1 ? 3 : side == 2 ? 3 - step : 0;
    const double y = (side == 0   ? 0
                      : side == 1 ? step
                      : side == 2 ? 3
                                  : 3 - step) +
                     (i == 4 ? y_error : 0.0);
    const double heading = 0.5 * 3.14159265358979 * side + turn;
    text += fmt::format("{} {} {} 0.5 0 0 {} {}\n", i, c * x - s * y + shift, s * x + c * y - shift,
                        std::sin(0.5 * heading), std::cos(0.5 * heading));
  }
  return text;
}

/// Field `k` (0-based) of the CSV line that starts with `start` (NaN when there is none).
double eval_cli_csv_field(const std::string& csv, const std::string& start, int k) {
  const auto at = csv.find("\n" + start);
  if (at == std::string::npos) return NAN;
  std::size_t pos = at + 1;
  for (int i = 0; i < k; ++i) pos = csv.find(',', pos) + 1;
  return std::stod(csv.substr(pos, csv.find_first_of(",\n", pos) - pos));
}

struct EvalCliFiles {
  TempDir dir{"eval_cli"};
  std::string ref = (dir.path() / "ref.tum").string();
  std::string est = (dir.path() / "est.tum").string();
  std::string file(const std::string& name, const std::string& text) const {
    const auto path = dir.path() / name;
    write_file(path, text);
    return path.string();
  }
};

TEST(EvalCli, ApeByHandAndAlignmentStatedInJson) {
  EvalCliFiles f;
  write_file(f.ref, eval_cli_square(0, 0));
  write_file(f.est, eval_cli_square(0, 0, 0.3));  // one pose 0.3 m off
  const auto r = run_cli("eval --ref " + f.ref + " --est " + f.est + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["pairs"], 12);
  EXPECT_EQ(j["alignment"]["kind"], "none");
  EXPECT_EQ(j["alignment"]["scale"], 1.0);
  const auto& t = j["ape"]["translation_m"];
  EXPECT_NEAR(t["mean"].get<double>(), 0.3 / 12, 1e-12);
  EXPECT_NEAR(t["rmse"].get<double>(), 0.3 / std::sqrt(12.0), 1e-12);
  EXPECT_NEAR(t["max"].get<double>(), 0.3, 1e-12);
  EXPECT_EQ(t["median"].get<double>(), 0.0);
  EXPECT_LE(t["mean_ci"][0].get<double>(), t["mean"].get<double>());
  // RPE over consecutive poses: the off pose enters pairs (3, 4) and (4, 5), 0.3 m each.
  EXPECT_EQ(j["rpe"]["pairs"], 11);
  EXPECT_NEAR(j["rpe"]["translation_m"]["max"].get<double>(), 0.3, 1e-12);
  EXPECT_NEAR(j["rpe"]["translation_m"]["mean"].get<double>(), 0.6 / 11, 1e-12);
  // Same seed, same intervals, for any thread count; the table names every row.
  EXPECT_EQ(run_cli("eval --ref " + f.ref + " --est " + f.est + " --json --threads 1").out, r.out);
  EXPECT_EQ(run_cli("eval --ref " + f.ref + " --est " + f.est + " --json --threads 2").out, r.out);
  EXPECT_NE(run_cli("eval --ref " + f.ref + " --est " + f.est + " --json --seed 2").out, r.out);
  const auto table = run_cli("eval --ref " + f.ref + " --est " + f.est);
  ASSERT_EQ(table.code, 0) << table.err;
  for (const char* row : {"APE translation [m]", "APE rotation [deg]", "RPE full |E - I|",
                          "rmse 95% CI", "alignment none"})
    EXPECT_NE(table.out.find(row), std::string::npos) << row << "\n" << table.out;
}

TEST(EvalCli, Se3AlignmentUndoesAnotherFrame) {
  EvalCliFiles f;
  write_file(f.ref, eval_cli_square(0, 0));
  write_file(f.est, eval_cli_square(5.0, 0.7));
  const auto raw =
      nlohmann::json::parse(run_cli("eval --ref " + f.ref + " --est " + f.est + " --json").out);
  EXPECT_GT(raw["ape"]["translation_m"]["mean"].get<double>(), 1.0);
  for (const char* kind : {"se2", "se3", "sim3"}) {
    const auto r = run_cli("eval --ref " + f.ref + " --est " + f.est + " --json --align " + kind);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["alignment"]["kind"], kind);
    EXPECT_NEAR(j["alignment"]["rotation_deg"].get<double>(), 0.7 * 180 / 3.14159265358979, 1e-9);
    EXPECT_NEAR(j["alignment"]["scale"].get<double>(), 1.0, 1e-12);
    EXPECT_LT(j["ape"]["translation_m"]["max"].get<double>(), 1e-9) << kind;
    EXPECT_LT(j["ape"]["rotation_deg"]["max"].get<double>(), 1e-6) << kind;
  }
}

TEST(EvalCli, RelationsAloneAndKittiFiles) {
  EvalCliFiles f;
  write_file(f.est, eval_cli_square(0, 0));
  // From pose 0 to pose 2: 2 m ahead (exact); from 2 to 3: 1 m ahead and a quarter turn,
  // recorded 0.1 m short.
  const std::string rel =
      f.file("r.relations", "0 2 2 0 0 0 0 0\n2 3 0.9 0 0 0 0 1.5707963267949\n");
  const auto r = run_cli("eval --est " + f.est + " --relations " + rel + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["relations"]["used"], 2);
  EXPECT_NEAR(j["relations"]["translation_m"]["mean"].get<double>(), 0.05, 1e-9);
  EXPECT_NEAR(j["relations"]["translation_sq_mean_m2"].get<double>(), 0.005, 1e-9);
  EXPECT_FALSE(j.contains("ape"));
  const std::string kitti = f.file("k.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n");
  const auto k = run_cli("eval --format kitti --ref " + kitti + " --est " + kitti + " --json");
  ASSERT_EQ(k.code, 0) << k.err;
  EXPECT_EQ(nlohmann::json::parse(k.out)["ape"]["translation_m"]["max"], 0.0);
}

TEST(EvalCli, BadFlagValuesAreUsageErrorsNamingTheFlag) {
  EvalCliFiles f;
  write_file(f.ref, eval_cli_square(0, 0));
  const std::string both = "eval --ref " + f.ref + " --est " + f.ref + " ";
  const struct {
    std::string args, flag, message;
  } rows[] = {
      {"eval --ref " + f.ref, "--est", "required"},
      {"eval --est " + f.ref, "--ref", "expected --ref FILE (or --relations FILE), got neither"},
      {both + "--format xml", "--format", "xml"},
      {both + "--align se4", "--align", "se4"},
      {"eval --est " + f.ref + " --relations " + f.ref + " --align se3", "--align",
       "expected --ref FILE to align with"},
      {both + "--delta 0", "--delta", "expected"},
      {both + "--delta nan", "--delta", "finite"},
      {both + "--delta 1.5", "--delta", "expected an integer number of frames, got 1.5"},
      {both + "--delta-unit km", "--delta-unit", "km"},
      {both + "--max-diff -1", "--max-diff", "expected"},
      {both + "--max-diff inf", "--max-diff", "finite"},
      {both + "--offset nan", "--offset", "finite"},
      {both + "--seed -1", "--seed", "expected an integer in [0, 2^64 - 1]"},
  };
  for (const auto& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, 2) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.flag), std::string::npos) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.message), std::string::npos) << row.args << "\n" << r.err;
  }
}

TEST(EvalCli, BadFilesAreErrorsNamingFileAndLine) {
  EvalCliFiles f;
  write_file(f.ref, eval_cli_square(0, 0));
  const std::string bad = f.file("bad.tum", "# c\n0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 1\n");
  const std::string late = f.file("late.tum", "100 0 0 0 0 0 0 1\n101 1 0 0 0 0 0 1\n");
  const std::string line = f.file("line.tum",
                                  "0 0 0 0 0 0 0 1\n0.1 1 0 0 0 0 0 1\n"
                                  "0.2 2 0 0 0 0 0 1\n");
  const std::string rel = f.file("bad.rel", "0 0.1 1 0 0 0 0\n");
  const std::string far = f.file("far.rel", "50 51 1 0 0 0 0 0\n");
  const std::string est = " --est " + f.ref;
  const struct {
    std::string args, message;
  } rows[] = {
      {"eval --ref " + f.ref + " --est " + bad, "eval --est: " + bad + ":3: expected 8 fields"},
      {"eval --ref " + bad + est, "eval --ref: " + bad + ":3:"},
      {"eval --ref " + f.ref + " --est " + f.file("nan.tum", "0 0 0 nan 0 0 0 1\n"),
       "nan.tum:1: field 4 (z): expected a finite number, got 'nan'"},
      {"eval --ref " + f.ref + " --est " + f.file("q.tum", "0 0 0 0 0 0 0 2\n"),
       "q.tum:1: expected a unit quaternion"},
      {"eval --ref " + f.ref + " --est " + f.file("back.tum", "1 0 0 0 0 0 0 1\n0 0 0 0 0 0 0 1\n"),
       "back.tum:2: expected a time after 1"},
      {"eval --ref " + (f.dir.path() / "missing.tum").string() + est, "missing.tum"},
      {"eval --format kitti --ref " + f.ref + est, "ref.tum:2: expected 12 fields"},
      {"eval --ref " + f.ref + " --est " + late, "raise --max-diff or set --offset"},
      {"eval --ref " + f.ref + est + " --delta 12", "eval --delta: relative pose error"},
      {"eval --ref " + line + " --est " + line + " --align se3", "not all on one line"},
      {"eval" + est + " --relations " + rel, "eval --relations: " + rel + ":1: expected 8 fields"},
      {"eval" + est + " --relations " + far, "got none of 1"},
      {"eval --ref " + f.ref + est + " --out " + f.ref, "--out"},
  };
  for (const auto& row : rows) {
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, 1) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.message), std::string::npos) << row.args << "\n" << r.err;
  }
}

TEST(EvalCli, OutWritesThePerPairErrors) {
  EvalCliFiles f;
  write_file(f.ref, eval_cli_square(0, 0));
  write_file(f.est, eval_cli_square(0, 0, 0.3));
  const auto out = f.dir.path() / "out";
  const auto r =
      run_cli("eval --ref " + f.ref + " --est " + f.est + " --quiet --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string ape = implicit::test::read_file(out / "ape.csv");
  EXPECT_EQ(ape.rfind("t,t,translation_m,rotation_deg,full\n", 0), 0u) << ape;
  EXPECT_NEAR(eval_cli_csv_field(ape, "4,4,", 2), 0.3, 1e-12) << ape;
  EXPECT_NEAR(eval_cli_csv_field(ape, "5,5,", 2), 0.0, 1e-12) << ape;
  const std::string rpe = implicit::test::read_file(out / "rpe.csv");
  EXPECT_EQ(rpe.rfind("t_i,t_j,translation_m,rotation_deg,full\n", 0), 0u) << rpe;
  EXPECT_NEAR(eval_cli_csv_field(rpe, "3,4,", 2), 0.3, 1e-12) << rpe;
}

}  // namespace
