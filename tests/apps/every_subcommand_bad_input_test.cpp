// One table of bad inputs over every subcommand: each row's exit code (2 for a refused flag, 1 for
// refused data) and the words its message must contain (the flag or the file it is about). The
// subcommands are read from `implicit --help`, so a new subcommand without rows here fails the
// test. Only refusals that happen before any work are listed: the table runs in seconds, also
// under the sanitizers. Deeper checks per subcommand live in bad_input_cli_test.cpp and the
// subcommand's own tests. Also what every subcommand shows: its own examples, and the version
// and commit in its JSON.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace implicit::test {
namespace {

struct SubcommandBadInput {
  std::string args;  ///< DIR stands for a fresh temporary folder
  int code;
  std::vector<std::string> says;
};

// The subcommands `implicit --help` lists (the lines under "Subcommands:").
std::set<std::string> every_subcommand_listed() {
  const auto r = run_cli("--help");
  std::istringstream in(r.out + r.err);
  std::set<std::string> names;
  bool listing = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("Subcommands:", 0) == 0) {
      listing = true;
      continue;
    }
    if (!listing) continue;
    if (line.size() < 3 || line.rfind("  ", 0) != 0 || line[2] == ' ') break;
    names.insert(line.substr(2, line.find(' ', 2) - 2));
  }
  return names;
}

// Rows of each subcommand's own flags and files (the generic flags are added for all below).
const std::map<std::string, std::vector<SubcommandBadInput>>& every_subcommand_rows() {
  static const std::map<std::string, std::vector<SubcommandBadInput>> rows = {
      {"arm",
       {{"arm --estimator nope", 2, {"--estimator", "nope"}}, {"arm --seed -1", 2, {"--seed"}}}},
      {"convert",
       {{"convert --out DIR/x.log", 2, {"--data"}},
        {"convert --data DIR/gone.mcap --out DIR/x.log", 1, {"gone.mcap"}},
        {"convert --data DIR/gone.mcap --out DIR/x.log --scan-topic ''", 2, {"--scan-topic"}},
        {"convert --data DIR/gone.mcap --out DIR/x.log --odom-topic ''", 2, {"--odom-topic"}},
        {"convert --data DIR/gone.mcap --out DIR/x.log --base-frame ''", 2, {"--base-frame"}},
        {"convert --data DIR/gone.mcap --out DIR/x.log --laser-frame ''", 2, {"--laser-frame"}}}},
      {"da",
       {{"da -N 1", 2, {"--members"}},
        {"da --model lorenz99", 2, {"--model", "lorenz99"}},
        {"da --method kalman", 2, {"--method", "kalman"}},
        {"da --model lorenz96 --dim 3", 2, {"--dim"}},
        {"da --forcing nan", 2, {"--forcing"}},
        {"da --seeds 0", 2, {"--seeds"}},
        {"da --jitter -1", 2, {"--jitter"}},
        {"da --inflation 0.5", 2, {"--inflation"}},
        {"da --resample-threshold 2", 2, {"--resample-threshold"}},
        {"da --map curved", 2, {"--map", "curved"}},
        {"da --regularisation shrink", 2, {"--regularisation", "shrink"}},
        {"da --regularisation cov --jitter -0.5", 2, {"--jitter"}},
        {"da --method implicit --regularisation cov --cycles 20",
         1,
         {"implicit particle filter", "jitter > 0"}},
        {"da --cycles -1", 2, {"--cycles"}},
        {"da --method implicit-smoother --lag 0", 2, {"--lag"}},
        {"da --method etkf --lag 2 --cycles 20", 1, {"--lag", "implicit smoother"}},
        {"da --method implicit-smoother --starts 0", 2, {"--starts"}},
        {"da --method implicit-smoother --starts 1001", 2, {"--starts"}},
        {"da --method implicit-smoother --starts 2.5", 2, {"--starts"}},
        {"da --method bootstrap --starts 2 --cycles 20", 1, {"--starts", "implicit smoother"}},
        {"da --method implicit-smoother --bandwidth 1.5", 2, {"--bandwidth"}},
        {"da --method implicit-smoother --bandwidth nan", 2, {"--bandwidth"}},
        {"da --method implicit-smoother --bandwidth 0 --cycles 20", 1, {"bandwidth h in (0, 1]"}},
        {"da --method etkf --bandwidth 0.5 --cycles 20", 1, {"--bandwidth", "implicit smoother"}},
        {"da --method implicit-smoother --map random --cycles 20",
         1,
         {"--map", "implicit smoother"}},
        {"da --method implicit-smoother --jitter 0.1 --cycles 20",
         1,
         {"--jitter", "implicit smoother"}},
        {"da --method implicit-smoother --regularisation cov --cycles 20",
         1,
         {"--regularisation", "implicit smoother"}},
        {"da --method implicit-smoother --resample-threshold 0.9 --cycles 20",
         1,
         {"--resample-threshold", "implicit smoother"}},
        {"da --method implicit --cycles 20", 1, {"implicit particle filter", "jitter > 0"}},
        {"da --obs-every 0", 2, {"--obs-every"}},
        {"da --obs-every 2.5", 2, {"--obs-every"}},
        {"da --model-noise -0.1", 2, {"--model-noise"}},
        {"da --model-noise nan", 2, {"--model-noise"}},
        {"da --method implicit-smoother --obs-every 2 --cycles 20",
         1,
         {"implicit smoother", "one model interval per observation"}},
        {"da --method implicit-smoother --model-noise 0.1 --cycles 20",
         1,
         {"implicit smoother", "model noise Q"}},
        {"da --method implicit --obs-every 2 --jitter 0.5 --regularisation cov --cycles 20",
         1,
         {"implicit particle filter", "2 model intervals per observation"}},
        // A filter that diverges (this seed's ETKF loses the finite numbers) is no result.
        {"da --model lorenz96 --obs-every 4 --model-noise 0.5 --method etkf -N 10 --inflation "
         "1.05 --seed 104 --seeds 1",
         1,
         {"1 of 1 runs diverged", "seed 104 at cycle", "rmse.a is not defined"}},
        {"da --model lorenz96 --forcing 1e6 --cycles 500", 1, {"forcing F = 1e+06 is unstable"}}}},
      {"eval",
       {{"eval", 2, {"--est"}},
        {"eval --ref DIR/gone.tum --est DIR/gone.tum", 1, {"gone.tum"}},
        {"eval --est DIR/gone.tum --delta 0", 2, {"--delta"}},
        {"eval --est DIR/gone.tum --align se4", 2, {"--align", "se4"}},
        {"eval --ref DIR/gone.tum --est DIR/gone.tum --plot ''", 2, {"--plot"}},
        {"eval --ref DIR/gone.tum --est DIR/gone.tum --plot DIR/gone/p.png", 2, {"--plot", "gone"}},
        {"eval --ref DIR/gone.tum --est DIR/gone.tum --plot DIR/p.gif", 2, {"--plot", ".png"}},
        {"eval --est DIR/gone.tum --relations DIR/gone.rel --plot DIR/p.png",
         2,
         {"--plot", "--ref"}}}},
      {"himmelblau",
       {{"himmelblau --runs 0", 2, {"--runs"}}, {"himmelblau --runs nan", 2, {"--runs"}}}},
      {"map",
       {{"map --out DIR/m.yaml", 2, {"--data"}},
        {"map --data DIR/gone.log --out DIR/m.yaml", 1, {"gone.log"}},
        {"map --data DIR/gone.log --out DIR/m.yaml --resolution 2", 2, {"--resolution"}},
        {"map --data DIR/gone.log --out DIR/m.yaml --pose-topic ''", 2, {"--pose-topic"}},
        {"map --data DIR/gone.log --out DIR/m.yaml --pose-topic /gt",
         1,
         {"--pose-topic", "gone.log"}},
        {"map --data DIR/gone.log --out DIR/m.yaml --scan-topic /s", 1, {"--scan-topic"}}}},
      {"mcl",
       {{"mcl --particles 0", 2, {"--particles"}},
        {"mcl --data DIR/gone.log", 1, {"gone.log"}},
        {"mcl --label-gate -1", 2, {"--label-gate"}},
        {"mcl --trajectory ''", 2, {"--trajectory"}},
        {"mcl --params DIR/gone.yaml", 2, {"--params", "gone.yaml"}},
        {"mcl --truth-trajectory DIR/gone/t.tum", 2, {"--truth-trajectory", "gone"}},
        {"mcl --init nowhere", 2, {"--init", "nowhere"}},
        // The choices drawn from the registries (experiments/motion_models.hpp, choices.hpp).
        {"mcl --model tank", 2, {"--model", "tank"}},
        {"mcl --method bogus", 2, {"--method", "bogus"}},
        {"mcl --sensor sonar", 2, {"--sensor", "sonar"}},
        {"mcl --sensor laser --laser-model sonar", 2, {"--laser-model", "sonar"}},
        {"mcl --sensor laser --data DIR/gone.mcap --scan-topic ''", 2, {"--scan-topic"}},
        {"mcl --sensor laser --data DIR/gone.mcap --odom-topic ''", 2, {"--odom-topic"}},
        {"mcl --sensor laser --data DIR/gone.mcap --base-frame b",
         1,
         {"--base-frame", "gone.mcap"}},
        {"mcl --sensor laser --data DIR/gone.mcap --laser-frame ''", 2, {"--laser-frame"}},
        {"mcl --sensor laser --data DIR/gone.mcap --estimate mode", 2, {"--estimate", "mode"}}}},
      {"proposal-gain",
       {{"proposal-gain --ratio-dt 0", 2, {"--ratio-dt"}},
        {"proposal-gain --ratios nan", 2, {"--ratios"}}}},
      {"reproduce",
       {{"reproduce --only nope --out DIR/r", 2, {"--only", "nope"}},
        {"reproduce --quick --report-only --out DIR/none", 1, {"DIR/none"}}}},
      {"simulate",
       {{"simulate", 2, {"--out"}},
        {"simulate --steps 0 --out DIR/s.log", 2, {"--steps"}},
        {"simulate --model car --out DIR/s.log", 2, {"--model", "car"}}}},
      {"slam",
       {{"slam --particles 0", 2, {"--particles"}},
        {"slam --data DIR/gone.log", 1, {"gone.log"}},
        {"slam --control-noise nan", 2, {"--control-noise"}},
        {"slam --model tank", 2, {"--model", "tank"}},
        {"slam --method bogus", 2, {"--method", "bogus"}},
        {"slam --sensor sonar", 2, {"--sensor", "sonar"}},
        {"slam --trajectory DIR/gone/e.tum", 2, {"--trajectory", "gone"}},
        {"slam --truth-trajectory ''", 2, {"--truth-trajectory"}},
        {"slam --sensor laser --method ekf --data DIR/a.log", 2, {"--method", "ekf"}},
        {"slam --sensor laser --method implicit", 2, {"--data"}},
        {"slam --sensor laser --gate-chi2 4 --data DIR/a.log", 2, {"--gate-chi2"}},
        {"slam --method gmapping", 2, {"--method", "--sensor laser"}},
        {"slam --alphas 0.1 0.1 0.1 0.1", 2, {"--alphas"}},
        {"slam --sensor laser --alphas 0.1 -1 0.1 0.1", 2, {"--alphas"}},
        {"slam --sensor laser --max-scans x", 2, {"--max-scans"}},
        {"slam --sensor laser --map-min-echoes 300", 2, {"--map-min-echoes"}},
        {"slam --sensor laser --map-out ''", 2, {"--map-out"}},
        {"slam --sensor laser --g2o ''", 2, {"--g2o"}},
        {"slam --sensor laser --g2o DIR/gone/g.g2o", 2, {"--g2o", "gone"}},
        {"slam --g2o DIR/gone/g.g2o", 2, {"--g2o", "gone"}},
        {"slam --scan-topic /scan", 2, {"--scan-topic", "--sensor laser"}},
        {"slam --sensor laser --data DIR/a.log --odom-topic ''", 2, {"--odom-topic"}},
        {"slam --sensor laser --data DIR/a.log --laser-frame l", 1, {"--laser-frame", "a.log"}},
        {"slam --sensor laser --data DIR/gone.log.gz", 1, {"gone.log.gz"}}}},
      {"slit", {{"slit --runs 0", 2, {"--runs"}}, {"slit --mode nope", 2, {"--mode", "nope"}}}},
  };
  return rows;
}

// The subcommand with its required flags (to files that do not exist: a flag error comes first).
std::string every_subcommand_required(const std::string& name) {
  if (name == "convert") return "convert --data DIR/gone.mcap --out DIR/x.log";
  if (name == "eval") return "eval --est DIR/gone.tum";
  if (name == "map") return "map --data DIR/gone.log --out DIR/m.yaml";
  if (name == "simulate") return "simulate --out DIR/s.log";
  return name;
}

TEST(EverySubcommand, HasRowsInTheBadInputTable) {
  const std::set<std::string> listed = every_subcommand_listed();
  ASSERT_GE(listed.size(), 10u) << "could not read the subcommands from implicit --help";
  for (const std::string& name : listed)
    EXPECT_TRUE(every_subcommand_rows().count(name)) << "no bad-input rows for '" << name << "'";
  for (const auto& [name, rows] : every_subcommand_rows())
    EXPECT_TRUE(listed.count(name)) << "rows for '" << name << "', which --help does not list";
}

TEST(EverySubcommand, RefusesBadInputNamingIt) {
  TempDir dir("every_subcommand");
  std::vector<SubcommandBadInput> all;
  for (const auto& [name, rows] : every_subcommand_rows()) {
    all.insert(all.end(), rows.begin(), rows.end());
    // Every subcommand (with its required flags): an unknown flag, and a common option out of
    // range.
    const std::string base = every_subcommand_required(name);
    all.push_back({base + " --no-such-flag", 2, {"--no-such-flag"}});
    all.push_back({base + " --threads nan", 2, {"--threads"}});
    all.push_back({base + " --threads 2000", 2, {"--threads"}});
  }
  for (SubcommandBadInput row : all) {
    for (std::size_t at = row.args.find("DIR"); at != std::string::npos;
         at = row.args.find("DIR", at + dir.path().string().size()))
      row.args.replace(at, 3, dir.path().string());
    const auto r = run_cli(row.args);
    EXPECT_EQ(r.code, row.code) << row.args << "\n" << r.err;
    for (std::string s : row.says) {
      if (const auto at = s.find("DIR"); at != std::string::npos)
        s.replace(at, 3, dir.path().string());
      EXPECT_NE(r.err.find(s), std::string::npos) << row.args << "\n" << r.err;
    }
  }
  // A refused command writes nothing.
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(Cli, SubcommandHelpShowsItsOwnExamples) {
  for (const char* name : {"slit", "arm", "himmelblau", "mcl", "slam", "reproduce"}) {
    const auto r = run_cli(std::string(name) + " --help");
    EXPECT_EQ(r.code, 0) << name;
    EXPECT_NE(r.out.find(std::string("implicit ") + name + " "), std::string::npos)
        << name << " shows no example of itself:\n"
        << r.out;
    EXPECT_EQ(r.out.find("implicit <subcommand> --help"), std::string::npos)
        << name << " shows the top-level examples:\n"
        << r.out;
  }
}

TEST(Cli, JsonCarriesVersionAndCommit) {
  const auto r = run_cli("arm --estimator closed-form --json --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j.contains("version") && j["version"].is_string()) << r.out;
  EXPECT_TRUE(j.contains("commit") && j["commit"].is_string()) << r.out;
}

}  // namespace
}  // namespace implicit::test
