// Every output of the command line is written under a temporary name and renamed when complete
// (implicit/core/output_file.hpp): a failed write names the flag and the file and leaves no
// temporary file; damaged --resume records are named and recomputed; `reproduce` stops its plot
// script with itself, lists its run's files in results.json and refuses a wrongly typed value.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::read_file;
using implicit::test::run_cli;
using implicit::test::run_shell;
using implicit::test::TempDir;
using implicit::test::write_file;
using nlohmann::json;

const std::string kOutputsSlit = "slit --runs 3 --naive-small 5 --naive-large 5 --quiet";

// Every file under `dir` (recursively) whose name says it is a temporary one.
std::vector<std::string> outputs_temporaries(const std::filesystem::path& dir) {
  std::vector<std::string> found;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    if (e.path().filename().string().find(".tmp") != std::string::npos)
      found.push_back(e.path().string());
  return found;
}

bool outputs_contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(OutputFiles, ARenameOntoAFolderFailsNamingTheFlagAndThePathAndLeavesNoTemporary) {
  TempDir dir("outputs_rename");
  struct Case {
    std::string command;
    std::filesystem::path blocked;  ///< made a folder, where the command writes a file
  };
  const std::filesystem::path d = dir.path();
  const std::vector<Case> cases = {
      {kOutputsSlit + " --out '" + (d / "slit").string() + "'", d / "slit" / "figure2_slit.csv"},
      {"simulate --model unicycle --steps 50 --quiet --out '" + (d / "sim" / "u.log").string() +
           "'",
       d / "sim" / "u.log"},
      {"simulate --model unicycle --steps 50 --quiet --out '" +
           (d / "simgz" / "u.log.gz").string() + "'",
       d / "simgz" / "u.log.gz"},
      {"reproduce --quick --only arm --no-figures --quiet --out '" + (d / "rep").string() + "'",
       d / "rep" / "table2_slit.csv"}};
  for (const auto& c : cases) {
    std::filesystem::create_directories(c.blocked);
    const auto r = run_cli(c.command);
    EXPECT_EQ(r.code, 1) << c.command << "\n" << r.err;
    EXPECT_TRUE(outputs_contains(r.err, "--out: " + c.blocked.string() +
                                            ": expected a writable output file, got a failed "
                                            "rename"))
        << c.command << "\n"
        << r.err;
    EXPECT_EQ(outputs_temporaries(c.blocked.parent_path()), std::vector<std::string>())
        << c.command;
  }
}

TEST(OutputFiles, ASuccessfulRunLeavesNoTemporary) {
  TempDir dir("outputs_success");
  const auto r = run_cli(kOutputsSlit + " --out '" + dir.path().string() + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto sim = run_cli("simulate --model unicycle --steps 300 --quiet --out '" +
                           (dir.path() / "u.log.gz").string() + "'");
  ASSERT_EQ(sim.code, 0) << sim.err;
  EXPECT_EQ(outputs_temporaries(dir.path()), std::vector<std::string>());
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "figure2_slit.csv"));
  // The gzip log is complete: mcl reads it back.
  const auto back = run_cli("mcl --model unicycle -M 20 --quiet --json --data '" +
                            (dir.path() / "u.log.gz").string() + "'");
  EXPECT_EQ(back.code, 0) << back.err;
}

// ---- --resume records ---------------------------------------------------------------------

std::vector<std::filesystem::path> outputs_records(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> found;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir / ".resume"))
    if (e.path().extension() == ".rec") found.push_back(e.path());
  std::sort(found.begin(), found.end());
  return found;
}

TEST(OutputFiles, DamagedResumeRecordsAreNamedOnStderrAndComputedAgain) {
  TempDir dir("outputs_resume");
  const std::string command = kOutputsSlit + " --json --out '" + dir.path().string() + "'";
  const auto first = run_cli(command);
  ASSERT_EQ(first.code, 0) << first.err;
  const auto records = outputs_records(dir.path());
  ASSERT_EQ(records.size(), 3u);
  std::string key;
  std::ifstream first_record(records[1]);
  std::getline(first_record, key);
  // 0: a 0-byte file (a full disk); 1: a number that is not one; 2: a count beyond any record.
  write_file(records[0], "");
  write_file(records[1], key + "\n6\nnot-a-number\n0x0p+0\n0x0p+0\n0x0p+0\n0x0p+0\n0x0p+0\n");
  write_file(records[2], key + "\n99999999999999\n");
  const auto again = run_cli(command + " --resume");
  ASSERT_EQ(again.code, 0) << again.err;
  for (const auto& [record, why] : std::vector<std::pair<std::filesystem::path, std::string>>{
           {records[0], "got an empty file"},
           {records[1], "expected 6 numbers, got 'not-a-number' on line 3"},
           {records[2],
            "expected a count of numbers in [0, 1048576] on line 2, got '99999999999999'"}})
    EXPECT_TRUE(outputs_contains(
        again.err, "implicit: --resume: " + record.string() + ": " + why + "; ignored, run "))
        << why << "\n"
        << again.err;
  const json a = json::parse(first.out), b = json::parse(again.out);
  for (const char* k : {"error_x_mean", "error_u_mean", "error_x_std"})
    EXPECT_EQ(a.at(k), b.at(k)) << k;
  // The recomputed runs' records were written again, whole.
  const auto third = run_cli(command + " --resume");
  ASSERT_EQ(third.code, 0) << third.err;
  EXPECT_FALSE(outputs_contains(third.err, "--resume")) << third.err;
}

// ---- reproduce ----------------------------------------------------------------------------

TEST(OutputFiles, SigtermDuringTheFiguresStopsThePlotScriptWithTheCommand) {
  TempDir dir("outputs_sigterm_figures");
  const auto plots = dir.path() / "plots";
  const auto out = dir.path() / "out";
  // A plot script that starts a figure, then writes long after: it must not get to.
  write_file(plots / "figure4.py",
             "import pathlib, sys, time\n"
             "d = pathlib.Path(sys.argv[1])\n"
             "(d / 'figure4.png').write_bytes(b'half a figure')\n"
             "(d / 'script_started').write_text('1')\n"
             "time.sleep(4)\n"
             "(d / 'late_write.txt').write_text('written after the command ended')\n");
  std::filesystem::create_directories(out);
  const auto r = run_shell(
      "{ IMPLICIT_PLOTS_DIR='" + plots.string() + "' '" + IMPLICIT_CLI +
      "' reproduce --quick --only arm --quiet --out '" + out.string() +
      "' & pid=$!; i=0; while [ ! -e '" + (out / "script_started").string() +
      "' ] && [ $i -lt 1200 ]; do sleep 0.1; i=$((i+1)); done; kill -TERM $pid; wait $pid; }");
  EXPECT_EQ(r.code, 128 + 15) << r.err;
  EXPECT_TRUE(outputs_contains(r.err, "implicit: stopped by SIGTERM;")) << r.err;
  ASSERT_TRUE(std::filesystem::exists(out / "script_started"));
  std::this_thread::sleep_for(std::chrono::seconds(5));  // past the script's sleep
  EXPECT_FALSE(std::filesystem::exists(out / "late_write.txt"));
  EXPECT_FALSE(std::filesystem::exists(out / "figure4.png")) << "the half-drawn figure stays";
  EXPECT_EQ(outputs_temporaries(out), std::vector<std::string>());
}

TEST(OutputFiles, ReproduceListsItsFilesWithARunIdAndRemovesAnEarlierRunsFiles) {
  TempDir dir("outputs_run_files");
  const std::string command =
      "reproduce --quick --only arm --no-figures --quiet --out '" + dir.path().string() + "'";
  const auto first = run_cli(command);
  ASSERT_TRUE(first.code == 0 || first.code == 3) << first.err;
  json results = json::parse(read_file(dir.path() / "results.json"));
  ASSERT_TRUE(results.contains("run_id"));
  const auto files = results.at("files").get<std::vector<std::string>>();
  for (const char* f : {"figure4_arm.csv", "table2_slit.csv", "results.json", "report.md"})
    EXPECT_NE(std::find(files.begin(), files.end(), f), files.end()) << f;
  for (const auto& f : files) EXPECT_TRUE(std::filesystem::exists(dir.path() / f)) << f;
  // As if the earlier run had written one more figure: the next run removes it, and leaves alone
  // what no run listed (and anything outside the folder).
  write_file(dir.path() / "figure1_guided.csv", "stale\n");
  write_file(dir.path() / "notes.txt", "mine\n");
  write_file(dir.path().parent_path() / "outputs_outside.txt", "outside\n");
  results["files"].push_back("figure1_guided.csv");
  results["files"].push_back("../outputs_outside.txt");
  write_file(dir.path() / "results.json", results.dump(2));
  const auto second = run_cli(command);
  ASSERT_TRUE(second.code == 0 || second.code == 3) << second.err;
  const json again = json::parse(read_file(dir.path() / "results.json"));
  EXPECT_NE(again.at("run_id"), results.at("run_id"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "figure1_guided.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "notes.txt"));
  EXPECT_TRUE(std::filesystem::exists(dir.path().parent_path() / "outputs_outside.txt"));
  std::filesystem::remove(dir.path().parent_path() / "outputs_outside.txt");
  const auto listed = again.at("files").get<std::vector<std::string>>();
  EXPECT_EQ(std::find(listed.begin(), listed.end(), "notes.txt"), listed.end());
  // --report-only keeps the run's id and its list.
  const auto redo =
      run_cli("reproduce --report-only --no-figures --quiet --out '" + dir.path().string() + "'");
  ASSERT_TRUE(redo.code == 0 || redo.code == 3) << redo.err;
  const json redone = json::parse(read_file(dir.path() / "results.json"));
  EXPECT_EQ(redone.at("run_id"), again.at("run_id"));
  EXPECT_EQ(redone.at("files"), again.at("files"));
}

TEST(OutputFiles, AWronglyTypedResultIsRefusedNamingTheKeyAndTheFile) {
  TempDir dir("outputs_typed");
  const auto file = dir.path() / "results.json";
  const json run = {{"label", "slit corrected M=50"},
                    {"status", "ok"},
                    {"settings", {{"mode", "corrected"}, {"samples", 50}}},
                    {"result", {{"runs", 10}, {"error_x_mean", 1.5}}}};
  const json results = {
      {"schema", "implicit-reproduce-1"},
      {"experiments", {{"slit", {{"status", "ok"}, {"runs", json::array({run})}}}}}};
  // A string where a result belongs, a name where a number setting belongs, a number where a
  // name belongs: each refused, naming the file and the key path, and no table written.
  const std::vector<std::tuple<std::string, json, std::string>> cases = {
      {"result/error_x_mean", "1.5; rm -rf",
       "expected a number or null at /experiments/slit/runs/0/result/error_x_mean, got \"1.5; "
       "rm -rf\" (a string)"},
      {"settings/samples", "fifty",
       "expected a number or null at /experiments/slit/runs/0/settings/samples, got \"fifty\" "
       "(a string)"},
      {"settings/mode", 3,
       "expected a name (a string) at /experiments/slit/runs/0/settings/mode, got 3 (a number)"}};
  for (const auto& [where, value, message] : cases) {
    json edited = results;
    edited[json::json_pointer("/experiments/slit/runs/0/" + where)] = value;
    write_file(file, edited.dump(2));
    const auto r =
        run_cli("reproduce --report-only --no-figures --quiet --out '" + dir.path().string() + "'");
    EXPECT_EQ(r.code, 1) << where << "\n" << r.err;
    EXPECT_TRUE(outputs_contains(r.err, file.string() + ": " + message)) << where << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "table2_slit.csv")) << where;
  }
  // The same file with the right types is accepted.
  write_file(file, results.dump(2));
  const auto good =
      run_cli("reproduce --report-only --no-figures --quiet --out '" + dir.path().string() + "'");
  const std::string table = read_file(dir.path() / "table2_slit.csv");
  EXPECT_TRUE(outputs_contains(table, "\ncorrected,50,10,1.5,")) << table << good.err;
}

}  // namespace
