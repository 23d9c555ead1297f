// The report's text file (data/report/text.json): its keys are exactly the keys the report looks
// up, and a missing, malformed or incomplete file stops with an error naming the file and the key.
//
// The keys are recorded while reports are built from the results.json of the fuzzing corpus and
// from variants of it that take the branches the corpus file does not (a figure drawn, full
// settings, a failed run without a message, a 400-run Himmelblau row, our Table 4 CSV readable
// and not, the proposal-gain tables, the laser tables with a run that failed).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"
#include "apps/report.hpp"
#include "apps/report_parts.hpp"
#include "implicit/core/error.hpp"

namespace {

namespace report = implicit::app::report;
using implicit::test::read_file;
using implicit::test::run_cli;
using implicit::test::TempDir;
using implicit::test::write_file;
using nlohmann::json;

json corpus_results() {
  return json::parse(read_file(std::filesystem::path(IMPLICIT_SOURCE_DIR) /
                               "fuzz/corpus/results_json/quick_run.json"));
}

/// The corpus file changed so that the report takes its other branches.
json variant(json results) {
  results["quick"] = false;
  results["figures"]["figure2"] = {{"status", "ok"}, {"files", {"figure2.png"}}};
  auto& himmelblau = results["experiments"]["himmelblau"]["runs"];
  json many = himmelblau[0];
  many["settings"]["runs"] = 400;
  himmelblau.push_back(many);
  results["experiments"]["slam"]["runs"][0].erase("error");
  results["experiments"]["proposal_gain"] = {
      {"status", "ok"},
      {"runs",
       {{{"label", "proposal_gain"},
         {"settings", json::object()},
         {"status", "ok"},
         {"result", {{"points", json::array()}, {"carpark_ratio", {{"A", 0.5}}}}}}}}};
  // laser_mcl: a tracking and a global configuration that ran, and one that failed.
  const json summary = {{"mean", 0.1}, {"se", 0.01}, {"median", 0.1}};
  results["experiments"]["laser_mcl"] = {
      {"status", "partial"},
      {"runs",
       {{{"label", "laser tracking implicit M=25"},
         {"settings", {{"proposal", "implicit"}, {"particles", 25}, {"start", "known"}}},
         {"status", "ok"},
         {"result",
          {{"data", "aces-corrected.log.gz"},
           {"runs", 2},
           {"scans_in_log", 440},
           {"updates", 40},
           {"map", {{"width", 100}, {"height", 80}, {"resolution", 0.05}}},
           {"dataset", {{"load_seconds", 0.5}, {"from_cache", false}}},
           {"position_rmse_m", summary},
           {"ess_fraction", summary},
           {"cpu_us_per_update", summary},
           {"cpu_us_per_update_per_particle", 2.0},
           {"lost_runs", 0}}}},
        {{"label", "laser global bootstrap M=1000"},
         {"settings", {{"proposal", "bootstrap"}, {"particles", 1000}, {"start", "global"}}},
         {"status", "ok"},
         {"result",
          {{"runs", 2},
           {"global_successes", 1},
           {"updates_to_converge_median", 3},
           {"cpu_us_per_update", summary}}}},
        {{"label", "laser global implicit M=200"},
         {"settings", {{"proposal", "implicit"}, {"particles", 200}, {"start", "global"}}},
         {"status", "failed"},
         {"error", "no such file"}}}}};
  return results;
}

template <typename F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

TEST(ReportText, TheFileHasExactlyTheKeysTheReportLooksUp) {
  TempDir dir("report_text_keys");
  const report::Text text = report::report_text();
  const report::parts::Numbers numbers{report::paper_numbers(), report::reference_numbers(), text};
  const json results = corpus_results();
  report::parts::build_report_with(results, dir.path(), numbers);
  write_file(dir.path() / "table4_himmelblau.csv", "k,newton\n0,1.5\n");
  report::parts::build_report_with(variant(results), dir.path(), numbers);
  write_file(dir.path() / "table4_himmelblau.csv", "k,newton\n0\n");  // a row too short
  report::parts::build_report_with(variant(results), dir.path(), numbers);

  const std::set<std::string> used = text.used();
  const auto all = text.keys();
  const std::set<std::string> in_file(all.begin(), all.end());
  std::vector<std::string> unused, missing;
  std::set_difference(in_file.begin(), in_file.end(), used.begin(), used.end(),
                      std::back_inserter(unused));
  std::set_difference(used.begin(), used.end(), in_file.begin(), in_file.end(),
                      std::back_inserter(missing));
  EXPECT_TRUE(unused.empty()) << "in text.json, never looked up: " << json(unused).dump();
  EXPECT_TRUE(missing.empty()) << "looked up, not in text.json: " << json(missing).dump();
}

TEST(ReportText, AnArrayIsJoinedWithOneSpaceAndListsAreNumberedKeys) {
  TempDir dir("report_text_join");
  const auto file = dir.path() / "text.json";
  write_file(file, R"({"p": ["One.", "Two {n}."], "l.1": "a", "l.2": ["b", "c"], "l.4": "d"})");
  const report::Text text = report::read_text_file(file);
  EXPECT_EQ(text("p"), "One. Two {n}.");
  EXPECT_EQ(text.format("p", fmt::arg("n", 2)), "One. Two 2.");
  // A list ends at the first missing number.
  EXPECT_EQ(text.items("l"), (std::vector<std::string>{"a", "b c"}));
}

TEST(ReportText, MissingFileIsAnErrorNamingItAndTheVariable) {
  TempDir dir("report_text_missing");
  const auto file = dir.path() / "text.json";
  EXPECT_THROW(report::read_text_file(file), implicit::InvalidArgument);
  const std::string m = message_of([&] { report::read_text_file(file); });
  EXPECT_NE(m.find(file.string()), std::string::npos) << m;
  EXPECT_NE(m.find("IMPLICIT_DATA_DIR"), std::string::npos) << m;
}

TEST(ReportText, MalformedFilesAreErrorsNamingTheFile) {
  TempDir dir("report_text_malformed");
  const auto file = dir.path() / "text.json";
  for (const std::string text : {"{\"a\": \"x\"", "[\"a\"]", "{\"a\": 1}", "{\"a\": []}",
                                 "{\"a\": [\"x\", 2]}", "{\"a\": {\"b\": \"x\"}}"}) {
    SCOPED_TRACE(text);
    write_file(file, text);
    EXPECT_THROW(report::read_text_file(file), implicit::ParseError);
    const std::string m = message_of([&] { report::read_text_file(file); });
    EXPECT_NE(m.find(file.string()), std::string::npos) << m;
  }
  write_file(file, "{\"a\": \"x\"");
  EXPECT_NE(message_of([&] { report::read_text_file(file); }).find("not valid JSON"),
            std::string::npos);
}

TEST(ReportText, AMissingKeyIsAnErrorNamingTheKeyAndTheFile) {
  TempDir dir("report_text_key");
  const auto file = dir.path() / "text.json";
  write_file(file, R"({"a": "x"})");
  const report::Text text = report::read_text_file(file);
  EXPECT_THROW(text("slit.heading"), implicit::ParseError);
  for (const std::string& m :
       {message_of([&] { text("slit.heading"); }), message_of([&] { text.format("slit.heading"); }),
        message_of([&] { text.items("slit.heading"); })}) {
    EXPECT_NE(m.find("slit.heading"), std::string::npos) << m;
    EXPECT_NE(m.find(file.string()), std::string::npos) << m;
  }
}

TEST(ReportText, ATextThatCannotBeFormattedIsAnErrorNamingTheKey) {
  TempDir dir("report_text_format");
  const auto file = dir.path() / "text.json";
  write_file(file, R"({"open": "runs {n", "unknown": "runs {m}", "spec": "{n:.2q}"})");
  const report::Text text = report::read_text_file(file);
  for (const std::string key : {"open", "unknown", "spec"}) {
    SCOPED_TRACE(key);
    EXPECT_THROW(text.format(key, fmt::arg("n", 3)), implicit::ParseError);
    const std::string m = message_of([&] { text.format(key, fmt::arg("n", 3)); });
    EXPECT_NE(m.find("\"" + key + "\""), std::string::npos) << m;
  }
}

TEST(ReportText, AReportWithAKeyMissingStopsNamingTheKey) {
  TempDir dir("report_text_incomplete");
  json strings = json::parse(
      read_file(std::filesystem::path(IMPLICIT_SOURCE_DIR) / "data" / "report" / "text.json"));
  strings.erase("mcl.heading");
  const auto file = dir.path() / "text.json";
  write_file(file, strings.dump());
  const report::parts::Numbers numbers{report::paper_numbers(), report::reference_numbers(),
                                       report::read_text_file(file)};
  EXPECT_THROW(report::parts::build_report_with(corpus_results(), dir.path(), numbers),
               implicit::ParseError);
  const std::string m =
      message_of([&] { report::parts::build_report_with(corpus_results(), dir.path(), numbers); });
  EXPECT_NE(m.find("mcl.heading"), std::string::npos) << m;
  EXPECT_NE(m.find(file.string()), std::string::npos) << m;
}

TEST(ReportText, ReproduceStopsBeforeTheRunsWhenTheTextFileIsBad) {
  TempDir dir("report_text_cli");
  const auto data = dir.path() / "data" / "report";
  const auto source = std::filesystem::path(IMPLICIT_SOURCE_DIR) / "data" / "report";
  std::filesystem::create_directories(data);
  for (const char* name : {"paper.json", "reference.json"})
    std::filesystem::copy_file(source / name, data / name);
  write_file(data / "text.json", "{\"report.heading\": ");
  setenv("IMPLICIT_DATA_DIR", (dir.path() / "data").c_str(), 1);
  const auto r = run_cli("reproduce --quick --only arm --no-figures --quiet --out '" +
                         (dir.path() / "out").string() + "'");
  unsetenv("IMPLICIT_DATA_DIR");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find((data / "text.json").string()), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "out" / "results.json"));
}

}  // namespace
