// `implicit eval --plot FILE`: the figure of the aligned trajectories and the APE along the path,
// drawn by python/plots/eval_plot.py. The PNG is checked for what a reader sees: its size, and
// both paths' colours drawn over many pixels; PDF and SVG by their signatures; a bad --plot is
// refused before any file is read, and a python without matplotlib fails naming --plot and
// leaving no file.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"

namespace {

using implicit::test::read_file;
using implicit::test::run_cli;
using implicit::test::run_shell;
using implicit::test::TempDir;

std::string eval_plot_args(const std::string& plot) {
  const std::string data = std::string(IMPLICIT_SOURCE_DIR) + "/data/trajectories/";
  return "eval --ref " + data + "circle_ref.tum --est " + data +
         "circle_est.tum --align se2 --json --plot " + plot;
}

std::uint32_t eval_plot_big_endian(const std::string& bytes, std::size_t at) {
  std::uint32_t v = 0;
  for (std::size_t k = 0; k < 4; ++k) v = (v << 8) | static_cast<unsigned char>(bytes[at + k]);
  return v;
}

TEST(EvalPlotCli, DrawsBothPathsIntoAPng) {
  TempDir dir("eval_plot_png");
  const std::string png = (dir.path() / "circle.png").string();
  const auto r = run_cli(eval_plot_args(png));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["plot"], png);
  const std::string bytes = read_file(png);
  ASSERT_GT(bytes.size(), 24u);
  // The PNG signature, then the IHDR chunk: 12 x 5 inches at 150 dpi.
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(bytes.substr(12, 4), "IHDR");
  EXPECT_EQ(eval_plot_big_endian(bytes, 16), 1800u);
  EXPECT_EQ(eval_plot_big_endian(bytes, 20), 750u);
  // Not a blank canvas: the reference's colour (#1fa0a8) and the estimate's (#d62728) each cover
  // many pixels (a 40-pose circle at 1 px or more is thousands; the legend swatches alone are
  // under 100).
  const std::string count =
      "import sys, numpy as np, matplotlib.image as m; a = (m.imread(sys.argv[1])[..., :3] * 255)"
      ".round(); n = lambda c: int((np.abs(a - c).max(axis=2) <= 40).sum()); "
      "print(n([0x1f, 0xa0, 0xa8]), n([0xd6, 0x27, 0x28]))";
  const auto c = run_shell("/usr/bin/python3 -c '" + count + "' " + png);
  ASSERT_EQ(c.code, 0) << c.err;
  int reference = 0, estimate = 0;
  std::istringstream(c.out) >> reference >> estimate;
  EXPECT_GT(reference, 1000) << c.out;
  EXPECT_GT(estimate, 500) << c.out;
  // No temporary name left beside it.
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1);
}

TEST(EvalPlotCli, PdfAndSvgByTheirNames) {
  TempDir dir("eval_plot_formats");
  const std::string pdf = (dir.path() / "c.pdf").string(), svg = (dir.path() / "c.svg").string();
  ASSERT_EQ(run_cli(eval_plot_args(pdf)).code, 0);
  ASSERT_EQ(run_cli(eval_plot_args(svg)).code, 0);
  EXPECT_EQ(read_file(pdf).substr(0, 5), "%PDF-");
  EXPECT_NE(read_file(svg).find("<svg"), std::string::npos);
}

TEST(EvalPlotCli, BadPlotIsRefusedBeforeAnyWork) {
  TempDir dir("eval_plot_bad");
  const std::string gone = (dir.path() / "gone.tum").string();
  struct Row {
    std::string args;
    std::string says;
  };
  // The files do not exist: a refusal naming --plot (exit 2) comes before they are read.
  const Row rows[] = {
      {"--ref " + gone + " --est " + gone + " --plot ''", "--plot"},
      {"--ref " + gone + " --est " + gone + " --plot " + (dir.path() / "none" / "p.png").string(),
       "none"},
      {"--ref " + gone + " --est " + gone + " --plot " + (dir.path() / "p.jpg").string(), ".png"},
      {"--est " + gone + " --relations " + gone + " --plot " + (dir.path() / "p.png").string(),
       "--ref"},
  };
  for (const Row& row : rows) {
    const auto r = run_cli("eval " + row.args);
    EXPECT_EQ(r.code, 2) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find("--plot"), std::string::npos) << row.args << "\n" << r.err;
    EXPECT_NE(r.err.find(row.says), std::string::npos) << row.args << "\n" << r.err;
    EXPECT_EQ(r.err.find("gone.tum"), std::string::npos) << row.args << "\n" << r.err;
  }
}

TEST(EvalPlotCli, PythonWithoutMatplotlibFailsNamingPlotAndLeavesNoFile) {
  TempDir dir("eval_plot_no_matplotlib");
  // Debian's python3 without its site packages (-S) has neither numpy nor matplotlib.
  const auto python = dir.path() / "python3";
  std::ofstream(python) << "#!/bin/sh\nexec /usr/bin/python3 -S \"$@\"\n";
  std::filesystem::permissions(python, std::filesystem::perms::owner_all);
  const std::string png = (dir.path() / "p.png").string();
  const auto r = run_shell("IMPLICIT_PYTHON='" + python.string() + "' '" + IMPLICIT_CLI + "' " +
                           eval_plot_args(png));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("--plot"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("matplotlib"), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1);  // the python3 wrapper only
}

}  // namespace
