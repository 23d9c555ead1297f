// What the commands print for a reader: the reproduce summary's columns line up whatever the
// width of their cells, one run is "1 run", a log that is not the Car Park is named with its
// model instead of a Car Park config, progress counts never go back when workers finish together,
// and the Himmelblau table compares f(x_19) with the reference, whose standard error is known.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"
#include "apps/context.hpp"
#include "apps/plural.hpp"
#include "apps/report.hpp"
#include "apps/report_parts.hpp"

namespace {

namespace report = implicit::app::report;
using implicit::test::read_file;
using implicit::test::run_cli;
using implicit::test::TempDir;
using implicit::test::write_file;
using nlohmann::json;

std::vector<std::string> printed_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// Where (in code points) each cell of `line` starts: after the indent, cells are separated by
/// two or more blanks.
std::vector<std::size_t> printed_cell_starts(const std::string& line) {
  std::vector<std::size_t> starts;
  std::size_t column = 0, blanks = 0;
  bool first = true;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const auto c = static_cast<unsigned char>(line[i]);
    if ((c & 0xC0) == 0x80) continue;  // a UTF-8 continuation byte: same code point
    if (c == ' ') {
      ++blanks;
    } else {
      if (first || blanks >= 2) starts.push_back(column);
      first = false;
      blanks = 0;
    }
    ++column;
  }
  return starts;
}

TEST(PrintedText, AlignedColumnsLineUpForAnyWidthAndUtf8) {
  const std::vector<std::vector<std::string>> rows = {
      {"slit", "ok", "1.5 s"},
      {"global_localization", "partial", "1234.5 s"},
      {"± – ✓", "failed", "0.0 s"},
      {"figure10", "ok"}};
  const std::string text = report::aligned_columns(rows, {false, false, true});
  const auto lines = printed_lines(text);
  ASSERT_EQ(lines.size(), rows.size()) << text;
  // Columns 1 and 2 start at the same place in every row that has them; the right-aligned
  // column 2 ends at the same place.
  const auto first = printed_cell_starts(lines[1]);
  ASSERT_EQ(first.size(), 3u) << lines[1];
  for (const auto& line : lines) {
    const auto starts = printed_cell_starts(line);
    ASSERT_GE(starts.size(), 2u) << line;
    EXPECT_EQ(starts[0], 2u) << line;  // the indent
    EXPECT_EQ(starts[1], first[1]) << text;
    if (starts.size() == 3) {
      EXPECT_EQ(report::text_width(line), report::text_width(lines[1])) << text;
    }
    EXPECT_NE(line.back(), ' ') << "trailing blanks: '" << line << "'";
  }
  // The widest first cell decides: two blanks after it.
  EXPECT_EQ(first[1], 2u + report::text_width("global_localization") + 2u);
  EXPECT_EQ(report::text_width("± – ✓"), 5u);
}

TEST(PrintedText, ReproduceSummaryColumnsLineUp) {
  TempDir dir("printed_reproduce");
  json results = json::parse(read_file(std::filesystem::path(IMPLICIT_SOURCE_DIR) /
                                       "fuzz/corpus/results_json/quick_run.json"));
  // The longest experiment name, so that a fixed column width would show.
  results["experiments"]["global_localization"] = {
      {"status", "ok"}, {"seconds", 12.5}, {"runs", json::array()}};
  write_file(dir.path() / "results.json", results.dump(2));
  const auto r =
      run_cli("reproduce --report-only --no-figures --out '" + dir.path().string() + "'");
  ASSERT_TRUE(r.code == 0 || r.code == 3) << r.code << r.err;
  std::vector<std::string> table;
  for (const auto& line : printed_lines(r.out))
    if (line.rfind("  ", 0) == 0) table.push_back(line);
  ASSERT_GE(table.size(), 6u) << r.out;
  const auto starts = printed_cell_starts(table[0]);
  ASSERT_GE(starts.size(), 2u) << table[0];
  bool saw_long = false, saw_figure = false;
  for (const auto& line : table) {
    EXPECT_EQ(printed_cell_starts(line).at(1), starts[1]) << r.out;
    saw_long |= line.find("global_localization") != std::string::npos;
    saw_figure |= line.find("figure1 ") != std::string::npos;
  }
  EXPECT_TRUE(saw_long && saw_figure) << r.out;
}

TEST(PrintedText, OneIsSingular) {
  EXPECT_EQ(implicit::app::counted(1, "run", "runs"), "1 run");
  EXPECT_EQ(implicit::app::counted(0, "run", "runs"), "0 runs");
  EXPECT_EQ(implicit::app::counted(2, "data set", "data sets"), "2 data sets");

  const auto himmelblau = run_cli("himmelblau --runs 1 --quiet");
  ASSERT_EQ(himmelblau.code, 0) << himmelblau.err;
  EXPECT_NE(himmelblau.out.find("1 run,"), std::string::npos) << himmelblau.out;
  EXPECT_EQ(himmelblau.out.find("1 runs"), std::string::npos) << himmelblau.out;
}

TEST(PrintedText, OneSkippedScanIsSingular) {
  TempDir dir("printed_skipped");
  const auto log = dir.path() / "one_extra_scan.log";
  {
    std::ofstream out(log);
    out << "vehicle unicycle dt=0.1\nlandmark 1 5 0\ninitial 0 0 0 0 0.1 0.1 0.01\n";
    for (int k = 1; k <= 20; ++k) out << "control " << 0.1 * k << " 1 0\n";
    for (int k = 1; k <= 19; ++k) {
      out << "scan " << 0.1 * k + 0.01 << " 1\nobs 5 1.5708 1\n";
      // A second scan on the first control: the schedule leaves it out.
      if (k == 1) out << "scan 0.12 1\nobs 5 1.5708 1\n";
    }
  }
  const auto r = run_cli("mcl -M 20 --runs 1 --data '" + log.string() + "' --allow-empty --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: 1 detection in 1 scan of"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("is not used"), std::string::npos) << r.err;
}

TEST(PrintedText, AnotherLogIsNamedWithItsModelNotACarParkConfig) {
  TempDir dir("printed_unicycle");
  const std::string log = (dir.path() / "u.log.gz").string();
  const auto sim = run_cli("simulate --model unicycle --seed 3 --steps 300 --out '" + log + "'");
  ASSERT_EQ(sim.code, 0) << sim.err;
  const auto r = run_cli("mcl --data '" + log + "' -M 20 --runs 1 --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("log " + log + ", unicycle model, 1 run:"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("config"), std::string::npos) << r.out;
}

// Workers tick together; each printed count is at least the one before (the count was read
// before the lock, so a worker that waited printed an older, smaller count after a newer one).
TEST(PrintedText, ProgressCountsNeverGoBack) {
  constexpr std::size_t kWorkers = 4, kTicks = 2500;
  testing::internal::CaptureStderr();
  {
    implicit::app::Progress progress("printed", kWorkers * kTicks, true);
    std::vector<std::thread> workers;
    for (std::size_t w = 0; w < kWorkers; ++w)
      workers.emplace_back([&] {
        for (std::size_t i = 0; i < kTicks; ++i) progress.tick();
      });
    for (auto& w : workers) w.join();
  }
  const std::string err = testing::internal::GetCapturedStderr();
  const std::regex pattern(R"(printed: (\d+)/(\d+) \((\d+)%\).*)");
  long last = -1;
  int lines = 0;
  for (const auto& line : printed_lines(err)) {
    std::smatch m;
    ASSERT_TRUE(std::regex_match(line, m, pattern)) << line;
    const long done = std::stol(m[1]);
    EXPECT_GE(done, last) << err;
    last = done;
    ++lines;
  }
  EXPECT_EQ(last, static_cast<long>(kWorkers * kTicks)) << err;
  EXPECT_GE(lines, 10) << err;
}

// One SLAM run reports its progress as it goes (steps), not only "1/1" at its end.
TEST(PrintedText, OneSlamRunShowsProgressWithinTheRun) {
  const auto r = run_cli("slam --method ekf --datasets 1 --threads 1");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("steps: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(10%)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(50%)"), std::string::npos) << r.err;
}

TEST(PrintedText, TheReportListsTheFiguresByNumber) {
  TempDir dir("printed_figures");
  const report::Text text = report::report_text();
  const report::parts::Numbers numbers{report::paper_numbers(), report::reference_numbers(), text};
  json results = json::parse(read_file(std::filesystem::path(IMPLICIT_SOURCE_DIR) /
                                       "fuzz/corpus/results_json/quick_run.json"));
  for (const char* key : {"figure1", "figure10", "figure2", "figure9"})
    results["figures"][key] = {{"status", "skipped"}, {"error", "--no-figures"}};
  const auto doc = report::parts::build_report_with(results, dir.path(), numbers);
  std::vector<std::string> order;
  for (const auto& b : doc.blocks())
    if (b.kind == report::Block::Kind::kTable && !b.table.header.empty() &&
        b.table.header[0] == text("figures.col.figure"))
      for (const auto& row : b.table.rows) order.push_back(row.at(0));
  EXPECT_EQ(order, (std::vector<std::string>{"figure1", "figure2", "figure9", "figure10"}));
}

TEST(PrintedText, HimmelblauFx19IsComparedWithTheReference) {
  TempDir dir("printed_himmelblau");
  const report::Text text = report::report_text();
  const report::parts::Numbers numbers{report::paper_numbers(), report::reference_numbers(), text};
  const double ref = numbers.reference["himmelblau"]["mean_f_x19"].get<double>();
  const double ref_se = numbers.reference["himmelblau"]["mean_f_x19_se"].get<double>();
  json results = json::parse(read_file(std::filesystem::path(IMPLICIT_SOURCE_DIR) /
                                       "fuzz/corpus/results_json/quick_run.json"));
  auto agree_cell = [&](double ours, double se) {
    auto& r = results["experiments"]["himmelblau"]["runs"][0]["result"];
    r["mean_f_before_last_step"] = ours;
    r["mean_f_before_last_step_se"] = se;
    const auto doc = report::parts::build_report_with(results, dir.path(), numbers);
    for (const auto& b : doc.blocks()) {
      if (b.kind != report::Block::Kind::kTable ||
          b.table.caption != text("himmelblau.table.caption"))
        continue;
      std::size_t col = 0;
      while (col < b.table.header.size() &&
             b.table.header[col] != text("himmelblau.table.col.agree_reference"))
        ++col;
      for (const auto& row : b.table.rows)
        if (row.at(0) == text("himmelblau.row.f_x19")) return row.at(col);
    }
    return std::string("no such row");
  };
  // Our SE 4/3 of the reference's: the combined SE is 5/3 of it (3-4-5); 4 combined SE off
  // agrees, 5 do not (the threshold is 4.5).
  const double combined = ref_se * 5.0 / 3.0;
  EXPECT_EQ(agree_cell(ref + 4.0 * combined, ref_se * 4.0 / 3.0), "✓");
  EXPECT_EQ(agree_cell(ref - 5.0 * combined, ref_se * 4.0 / 3.0), "✗");
}

}  // namespace
