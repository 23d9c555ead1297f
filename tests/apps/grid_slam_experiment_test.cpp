// Grid SLAM over seeds (experiments/grid_slam.hpp) and the grid_slam experiment of `implicit
// reproduce` (experiments/grid_slam_reproduce.hpp) on the first scans of the bundled ACES log:
// each run is the library's run_grid_slam with that seed, the summaries are the runs' mean and
// standard error, the CLI reports the same numbers, and the figure's files are the first run.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "apps/cli_runner.hpp"
#include "experiments/grid_slam_reproduce.hpp"
#include "implicit/core/error.hpp"

namespace implicit::experiments {
namespace {

using test::TempDir;

const std::filesystem::path kAcesLog =
    std::filesystem::path(IMPLICIT_SOURCE_DIR) / "data/carmen/aces-corrected.log.gz";

GridSlamSettings short_aces(slam::GridProposalKind kind) {
  GridSlamSettings s;
  s.data = kAcesLog;
  s.run.proposal = kind;
  s.run.filter.particles = 4;
  s.run.max_scans = 30;
  s.runs = 3;
  s.seed = 5;
  return s;
}

/// The rows of a CSV file as fields (empty fields kept).
std::vector<std::vector<std::string>> csv_rows(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, ',')) fields.push_back(f);
    if (!line.empty() && line.back() == ',') fields.emplace_back();
    rows.push_back(fields);
  }
  return rows;
}

TEST(GridSlamExperiment, EachRunIsTheLibrarysRunWithItsSeedAndTheSummaryIsTheirMeanAndSe) {
  const GridSlamSettings s = short_aces(slam::GridProposalKind::kImplicit);
  const auto log = cached_carmen_log(kAcesLog);
  std::vector<int> progress_runs;
  std::size_t last_done = 0, last_total = 0;
  const GridSlamResult r =
      run_grid_slam_experiment(s, *log, [&](int run, std::size_t done, std::size_t total) {
        progress_runs.push_back(run);
        last_done = done;
        last_total = total;
      });
  ASSERT_EQ(r.runs.size(), 3u);
  std::vector<double> t;
  for (int k = 0; k < 3; ++k) {
    slam::GridSlamRunOptions o = s.run;
    o.filter.seed = o.data_seed = s.seed + static_cast<std::uint64_t>(k);
    const slam::GridSlamRun direct = slam::run_grid_slam(*log, o);
    EXPECT_EQ(r.runs[k].seed, s.seed + static_cast<std::uint64_t>(k));
    EXPECT_EQ(r.runs[k].relation_translation_m, direct.relations.translation_mean) << k;
    EXPECT_EQ(r.runs[k].relation_rotation_deg, direct.relations.rotation_mean_deg) << k;
    EXPECT_EQ(r.runs[k].odometry_translation_m, direct.odometry_relations.translation_mean);
    EXPECT_EQ(r.runs[k].resamplings, direct.resamplings) << k;
    EXPECT_EQ(r.scans_processed, direct.processed);
    t.push_back(direct.relations.translation_mean);
  }
  // Mean and standard error by hand: sample sd over sqrt(3).
  const double mean = (t[0] + t[1] + t[2]) / 3.0;
  double ss = 0.0;
  for (double v : t) ss += (v - mean) * (v - mean);
  EXPECT_NEAR(r.relation_translation_m.mean, mean, 1e-15);
  EXPECT_NEAR(r.relation_translation_m.se, std::sqrt(ss / 2.0) / std::sqrt(3.0), 1e-15);
  // The seeds give different odometry, so three equal errors would mean one seed for all.
  EXPECT_GT(r.relation_translation_m.se, 0.0);
  // Progress after each filter step (every processed scan but the first, which initialises the
  // maps) of each run, in run order, the last one at the total.
  ASSERT_EQ(progress_runs.size(), 3 * (r.scans_processed - 1));
  EXPECT_EQ(last_done, r.scans_processed);
  EXPECT_EQ(last_total, r.scans_processed);
  EXPECT_EQ(progress_runs.front(), 0);
  EXPECT_EQ(progress_runs.back(), 2);
  EXPECT_FALSE(r.first.has_value());  // not asked to keep it
}

TEST(GridSlamExperiment, TheCliReportsTheExperimentsNumbers) {
  const GridSlamSettings s = short_aces(slam::GridProposalKind::kScanMatch);
  const GridSlamResult r = run_grid_slam_experiment(s, *cached_carmen_log(kAcesLog));
  const auto cli = test::run_cli(
      "slam --sensor laser --method gmapping -M 4 --max-scans 30 --datasets 3 --seed 5 --json "
      "--data '" +
      kAcesLog.string() + "'");
  ASSERT_EQ(cli.code, 0) << cli.err;
  const auto j = nlohmann::json::parse(cli.out);
  EXPECT_EQ(j["relation_translation_m"]["mean"].get<double>(), r.relation_translation_m.mean);
  EXPECT_EQ(j["relation_translation_m"]["se"].get<double>(), r.relation_translation_m.se);
  EXPECT_EQ(j["relation_rotation_deg"]["mean"].get<double>(), r.relation_rotation_deg.mean);
  EXPECT_EQ(j["scans_processed"], r.scans_processed);
  ASSERT_EQ(j["per_run"].size(), 3u);
  for (std::size_t k = 0; k < 3; ++k)
    EXPECT_EQ(j["per_run"][k]["relation_translation_m"].get<double>(),
              r.runs[k].relation_translation_m);
}

TEST(GridSlamExperiment, TheFigureFilesAreTheFirstRunsTrackRelationsAndMap) {
  TempDir dir("grid_slam_figure");
  GridSlamSettings s = short_aces(slam::GridProposalKind::kImplicit);
  s.runs = 2;
  const nlohmann::json j = run_grid_slam_reproduce(s, dir.path(), true);
  EXPECT_EQ(j["figure_files"],
            (nlohmann::json{"grid_slam_reference.csv", "grid_slam_track_implicit.csv",
                            "grid_slam_map.csv"}));
  EXPECT_EQ(j["datasets"], 2);
  // The first run again, kept whole.
  s.keep_first = true;
  s.runs = 1;
  const GridSlamResult r = run_grid_slam_experiment(s, *cached_carmen_log(kAcesLog));
  ASSERT_TRUE(r.first.has_value());
  const slam::GridSlamRun& run = *r.first;
  EXPECT_EQ(j["per_run"][0]["relation_translation_m"].get<double>(),
            run.relations.translation_mean);

  const auto ref = csv_rows(dir.path() / "grid_slam_reference.csv");
  const auto track = csv_rows(dir.path() / "grid_slam_track_implicit.csv");
  ASSERT_EQ(ref.size(), run.reference.size() + 1);
  ASSERT_EQ(track.size(), run.trajectory.size() + 1);
  EXPECT_EQ(track[0], (std::vector<std::string>{"scan", "time_s", "x_m", "y_m", "heading_rad",
                                                "relation_error_m"}));
  EXPECT_EQ(track[1][5], "");  // no relation ends at the first scan
  double sum = 0.0;
  for (std::size_t k = 0; k < run.trajectory.size(); ++k) {
    // Written with 4 decimals: within 5e-5 m.
    EXPECT_NEAR(std::stod(ref[k + 1][2]), run.reference[k].pose(0), 5e-5) << k;
    EXPECT_NEAR(std::stod(track[k + 1][2]), run.trajectory[k].pose(0), 5e-5) << k;
    EXPECT_NEAR(std::stod(track[k + 1][3]), run.trajectory[k].pose(1), 5e-5) << k;
    EXPECT_EQ(track[k + 1][1], ref[k + 1][1]);
    if (k > 0) sum += std::stod(track[k + 1][5]);
  }
  // The errors along the track are the run's relations: their mean is the run's score, to the
  // 6 significant digits written.
  const double mean = sum / static_cast<double>(run.trajectory.size() - 1);
  EXPECT_NEAR(mean, run.relations.translation_mean, 1e-5 * run.relations.translation_mean);

  std::size_t occupied = 0;
  for (int iy = 0; iy < run.map.height(); ++iy)
    for (int ix = 0; ix < run.map.width(); ++ix) occupied += run.map.is_occupied(ix, iy) ? 1 : 0;
  EXPECT_GT(occupied, 0u);
  EXPECT_EQ(csv_rows(dir.path() / "grid_slam_map.csv").size(), occupied + 1);
}

// Another log's map panel: the same files under its prefix, the same bytes.
TEST(GridSlamExperiment, APrefixNamesTheFilesOfAnotherLogsMapPanel) {
  TempDir plain("grid_slam_figure_plain"), named("grid_slam_figure_named");
  GridSlamSettings s = short_aces(slam::GridProposalKind::kImplicit);
  s.runs = 1;
  run_grid_slam_reproduce(s, plain.path(), true);
  const nlohmann::json j = run_grid_slam_reproduce(s, named.path(), true, {}, "grid_slam_aces");
  EXPECT_EQ(j["figure_files"],
            (nlohmann::json{"grid_slam_aces_reference.csv", "grid_slam_aces_track_implicit.csv",
                            "grid_slam_aces_map.csv"}));
  for (const char* part : {"reference", "track_implicit", "map"}) {
    const auto a = csv_rows(plain.path() / fmt::format("grid_slam_{}.csv", part));
    const auto b = csv_rows(named.path() / fmt::format("grid_slam_aces_{}.csv", part));
    EXPECT_GT(a.size(), 1u) << part;
    EXPECT_EQ(a, b) << part;
  }
  EXPECT_FALSE(std::filesystem::exists(named.path() / "grid_slam_map.csv"));
}

TEST(GridSlamExperiment, BadSettingsAndAMissingFirstRunAreNamed) {
  GridSlamSettings s = short_aces(slam::GridProposalKind::kBootstrap);
  s.runs = 0;
  EXPECT_THROW(
      {
        try {
          run_grid_slam_experiment(s, *cached_carmen_log(kAcesLog));
        } catch (const InvalidArgument& e) {
          EXPECT_NE(std::string(e.what()).find("at least one run, got 0"), std::string::npos)
              << e.what();
          throw;
        }
      },
      InvalidArgument);
  s.runs = 1;
  const GridSlamResult r = run_grid_slam_experiment(s, *cached_carmen_log(kAcesLog));
  TempDir dir("grid_slam_no_first");
  EXPECT_THROW(
      {
        try {
          write_grid_slam_figure_files(r, dir.path(), false);
        } catch (const InvalidArgument& e) {
          EXPECT_NE(std::string(e.what()).find("keep_first"), std::string::npos) << e.what();
          throw;
        }
      },
      InvalidArgument);
  // A log that cannot be read is named, and not cached as read.
  for (int attempt = 0; attempt < 2; ++attempt) {
    try {
      cached_carmen_log(std::filesystem::path(IMPLICIT_SOURCE_DIR) / "no-such.log");
      ADD_FAILURE() << "expected an error for a missing log";
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find("no-such.log"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace implicit::experiments
