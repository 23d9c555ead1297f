// The report's standard errors, its agreement test and the numbers files it compares with.
//
// The agreement cell is checked at its boundary with hand-made numbers whose combined standard
// error is exact in binary (3-4-5 triangles), so "exactly 4.5 combined SE" is representable and
// the ✓/✗ switch is tested where it happens, not somewhere near it.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"
#include "apps/report.hpp"
#include "implicit/core/error.hpp"

namespace {

namespace report = implicit::app::report;
using implicit::test::run_cli;
using implicit::test::TempDir;
using implicit::test::write_file;
using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- Agreement ----------------------------------------------------------------------------------

TEST(ReportAgreement, AgreesUpToExactlyFourAndAHalfCombinedStandardErrors) {
  // SE 3 and 4 combine to 5; the threshold is 22.5.
  EXPECT_EQ(report::agreement({22.5, 3.0}, {0.0, 4.0}), "✓");
  EXPECT_EQ(report::agreement({0.0, 3.0}, {22.5, 4.0}), "✓");  // symmetric in the sign
  EXPECT_EQ(report::agreement({22.5 + 1e-9, 3.0}, {0.0, 4.0}), "✗");
  EXPECT_EQ(report::agreement({10.0, 3.0}, {10.0 - 22.5 - 1e-9, 4.0}), "✗");
  EXPECT_EQ(report::agreement({7.0, 0.3}, {7.0, 0.4}), "✓");
}

TEST(ReportAgreement, AnExactValueOnOneSideUsesTheOtherSideAlone) {
  // A closed form has SE 0: the test is then |ours − exact| ≤ 4.5 SE_ours.
  EXPECT_EQ(report::agreement({1.0 + 4.5 * 0.25, 0.25}, {1.0, 0.0}), "✓");
  EXPECT_EQ(report::agreement({1.0 + 4.5 * 0.25 + 1e-9, 0.25}, {1.0, 0.0}), "✗");
}

TEST(ReportAgreement, NotComputableGivesADash) {
  EXPECT_EQ(report::agreement({1.0, kNaN}, {1.0, 0.1}), "–");  // one run: no SE of ours
  EXPECT_EQ(report::agreement({1.0, 0.1}, {1.0, kNaN}), "–");  // reference without sd
  EXPECT_EQ(report::agreement({kNaN, 0.1}, {1.0, 0.1}), "–");  // ours did not run
  EXPECT_EQ(report::agreement({1.0, 0.1}, {kNaN, 0.1}), "–");
  EXPECT_EQ(report::agreement({1.0, 0.0}, {1.0, 0.0}), "–");  // two exact values: no test
  EXPECT_EQ(report::agreement({1.0, -0.1}, {1.0, 0.1}), "–");
  EXPECT_EQ(report::agreement({kInf, 0.1}, {1.0, 0.1}), "–");
  EXPECT_EQ(report::agreement(report::Estimate{}, report::Estimate{}), "–");
}

// ---- Standard errors ----------------------------------------------------------------------------

TEST(ReportStandardError, IsTheSdOverTheRootOfTheRunCount) {
  EXPECT_DOUBLE_EQ(report::standard_error(json(2.0), json(4)), 1.0);
  EXPECT_DOUBLE_EQ(report::standard_error(json(0.63), json(100)), 0.063);
  EXPECT_DOUBLE_EQ(report::standard_error(json(0.0), json(9)), 0.0);
  // One run has no standard error; missing or invalid inputs neither.
  EXPECT_TRUE(std::isnan(report::standard_error(json(1.0), json(1))));
  EXPECT_TRUE(std::isnan(report::standard_error(json(), json(10))));
  EXPECT_TRUE(std::isnan(report::standard_error(json(1.0), json())));
  EXPECT_TRUE(std::isnan(report::standard_error(json(-1.0), json(10))));
  EXPECT_TRUE(std::isnan(report::standard_error(json("1"), json(10))));
}

TEST(ReportStandardError, FormatsWithTwoSignificantDigits) {
  EXPECT_EQ(report::format_se(0.0022), "0.0022");
  EXPECT_EQ(report::format_se(0.13), "0.13");
  EXPECT_EQ(report::format_se(0.063), "0.063");
  EXPECT_EQ(report::format_se(1.5), "1.5");
  EXPECT_EQ(report::format_se(16.0), "16");
  EXPECT_EQ(report::format_se(150.0), "150");
  EXPECT_EQ(report::format_se(0.0), "0");
  EXPECT_EQ(report::format_se(kNaN), "–");
  EXPECT_EQ(report::format_se(-0.1), "–");
  EXPECT_EQ(report::format_se(kInf), "–");
}

TEST(ReportStandardError, SpreadShowsTheStandardErrorOfTheMean) {
  const json r = {{"runs", 100}, {"e_mean", 2.7}, {"e_std", 0.75}, {"e_median", 2.47}};
  EXPECT_EQ(report::spread(r, "e", 2), "2.70 ± 0.75 (SE 0.075, med 2.47)");
  // SLAM results count data sets instead of runs.
  EXPECT_EQ(report::spread({{"datasets", 4}, {"e_mean", 5.0}, {"e_std", 1.2}}, "e", 2),
            "5.00 ± 1.20 (SE 0.60)");
  // One run: no SE; no sd: neither.
  EXPECT_EQ(report::spread({{"runs", 1}, {"e_mean", 5.0}, {"e_std", 0.0}}, "e", 1), "5.0 ± 0.0");
  EXPECT_EQ(report::spread({{"runs", 5}, {"e_mean", 5.0}}, "e", 1), "5.0");
  EXPECT_EQ(report::spread({{"runs", 5}}, "e", 1), "–");
}

// ---- Numbers files ------------------------------------------------------------------------------

std::string message_of(const std::filesystem::path& file) {
  try {
    report::read_numbers_file(file, {"table2"});
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

TEST(ReportNumbersFile, MissingFileIsAnErrorNamingIt) {
  TempDir dir("report_numbers_missing");
  const auto file = dir.path() / "paper.json";
  EXPECT_THROW(report::read_numbers_file(file, {}), implicit::InvalidArgument);
  EXPECT_NE(message_of(file).find(file.string()), std::string::npos) << message_of(file);
}

TEST(ReportNumbersFile, MalformedFilesAreErrorsNamingTheFile) {
  TempDir dir("report_numbers_malformed");
  const auto file = dir.path() / "reference.json";
  for (const std::string text : {"{\"source\": \"x\", \"table2\": {", "[1, 2]", "{\"table2\": {}}",
                                 "{\"source\": 3, \"table2\": {}}", "{\"source\": \"x\"}",
                                 "{\"source\": \"x\", \"table2\": 1}"}) {
    SCOPED_TRACE(text);
    write_file(file, text);
    EXPECT_THROW(report::read_numbers_file(file, {"table2"}), implicit::ParseError);
    EXPECT_NE(message_of(file).find(file.string()), std::string::npos) << message_of(file);
  }
  write_file(file, "{\"source\": \"x\", \"table2\": {\"runs\": 500}}");
  EXPECT_EQ(report::read_numbers_file(file, {"table2"})["table2"]["runs"], 500);
}

// Nesting is bounded while parsing (apps/json_input.hpp), before anything recurses over it.
TEST(ReportNumbersFile, NestingBeyondTheBoundIsAnErrorNamingTheFileAndTheLevel) {
  TempDir dir("report_numbers_deep");
  const auto file = dir.path() / "paper.json";
  write_file(file, "{\"source\": \"x\", \"table2\": " + std::string(20000, '[') +
                       std::string(20000, ']') + "}");
  EXPECT_THROW(report::read_numbers_file(file, {"table2"}), implicit::ParseError);
  EXPECT_NE(message_of(file).find(file.string() +
                                  ": expected JSON nested at most 64 levels deep, got an array or "
                                  "object at level 65"),
            std::string::npos)
      << message_of(file);
  // 64 levels are read.
  write_file(file, "{\"source\": \"x\", \"table2\": {\"a\": " + std::string(62, '[') +
                       std::string(62, ']') + "}}");
  EXPECT_NO_THROW(report::read_numbers_file(file, {"table2"}));
}

TEST(ReportNumbersFile, TheInstalledFilesHaveEveryTableTheReportReads) {
  // build/share/implicit/data mirrors the install (core/share_dir.hpp).
  const json paper = report::paper_numbers();
  const json reference = report::reference_numbers();
  EXPECT_EQ(paper["table2"]["samples"], json({10, 50, 100, 500}));
  EXPECT_EQ(paper["table2"]["runs"], 500);
  EXPECT_EQ(reference["table5"]["rows"].size(), 5u);
  EXPECT_EQ(reference["table6"]["datasets"], 50);
}

TEST(ReportNumbersFile, ReproduceStopsWithTheFileNameWhenANumbersFileIsBad) {
  TempDir dir("report_numbers_cli");
  write_file(dir.path() / "data" / "report" / "paper.json", "{\"source\": \"x\", \"table2\": ");
  setenv("IMPLICIT_DATA_DIR", (dir.path() / "data").c_str(), 1);
  const auto r = run_cli("reproduce --quick --only arm --no-figures --quiet --out '" +
                         (dir.path() / "out").string() + "'");
  unsetenv("IMPLICIT_DATA_DIR");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find((dir.path() / "data" / "report" / "paper.json").string()), std::string::npos)
      << r.err;
}

}  // namespace
