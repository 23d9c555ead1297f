// The per-particle maps of grid SLAM (slam/grid/tiled_grid.hpp) on the Intel Research Lab log
// (data/carmen/intel-corrected.log.gz: 180 beams per scan, its corrected laser poses), at 0.05 m
// cells with beams used up to 40 m (the laser experiments' map_max_range). The scans are those a
// MapUpdateGate with GMapping's defaults (1 m, 0.5 rad) lets through.
//  * MapUpdate/<grid>: one scan integrated into the map of the scans before it (tiled: a grid no
//    other grid shares; dense: robot::LogOddsGrid over the whole map's extent, for reference);
//  * Copy/<M>: resampling, M copies of the map of the whole log (per_particle: one copy);
//  * CopyOnWrite/<M>: each of M fresh copies integrates the next scan: the map update plus the
//    copies of the tiles it touches (counter tiles_copied, per particle);
//  * TileSize: the bytes one scan makes a particle copy, and the bytes of the map's index, for
//    tiles of 16, 32 and 64 cells a side (the choice of 32);
//  * Memory/<M>: a particle set of M maps over the first 60 gated scans, each scan integrated at
//    the reference pose plus noise (sd 0.05 m, 0.02 rad) and followed by resampling with random
//    parents; counters: the set's bytes per particle (index + distinct tiles / M), one map's
//    bytes alone, and the dense map's.
//  * ScanMatch/value, ScanMatch/derivatives: the scan likelihood of the last gated scan against
//    the map of the scans before (slam/grid/scan_match.hpp, 60 beams, 8 x 8 cells each), per
//    evaluation: what every proposal pays per particle per evaluation;
//  * Proposal/<name>: one particle's proposal for the last gated scan (odometry: the reference
//    increment perturbed with alphas 0.05), per particle per scan; counter evaluations;
//  * GridSlam/<name>: the whole log by the semi-synthetic protocol (slam::run_grid_slam, 8
//    particles, data seed 1), once; counters: the mean translational and rotational relation error
//    against the corrected poses over consecutive processed scans, CPU per processed scan, mean
//    ESS / N and evaluations per particle and scan; implicit_coarse4: with coarse-to-fine starts
//    at 4 cells (slam::CoarseStartOptions);
//  * GridSlamSeeds/<name>: the same over seeds 1..10: mean and standard deviation of the runs'
//    mean relation errors, and the mean CPU per processed scan.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "implicit/core/rng.hpp"
#include "implicit/core/share_dir.hpp"
#include "implicit/robot/carmen.hpp"
#include "implicit/robot/grid_mapping.hpp"
#include "implicit/slam/grid/grid_proposals.hpp"
#include "implicit/slam/grid/grid_slam.hpp"
#include "implicit/slam/grid/grid_slam_run.hpp"
#include "implicit/slam/grid/map_update_gate.hpp"
#include "implicit/slam/grid/scan_match.hpp"
#include "implicit/slam/grid/tiled_grid.hpp"

namespace {

using namespace implicit;
using robot::Pose;
using slam::TiledLogOddsGrid;

struct GridScene {
  std::vector<robot::LaserScan> scans;  // gated
  std::vector<Pose> poses;              // the laser's, so the mount is zero
  robot::GridMappingOptions options;
  TiledLogOddsGrid full;  // every gated scan but the last
};

const GridScene& grid_scene() {
  static const GridScene scene = [] {
    GridScene s;
    s.options = slam::GridSlamOptions{}.map;  // grid SLAM's: echoes counted (min_echoes 1)
    s.options.resolution = 0.05;
    s.options.max_range = 40.0;
    const std::filesystem::path file =
        find_share_dir("data", "IMPLICIT_DATA_DIR") / "carmen" / "intel-corrected.log.gz";
    const robot::CarmenLog log = robot::read_carmen(file);
    const slam::MapUpdateGate gate;
    for (std::size_t k = 0; k < log.scans.size(); ++k)
      if (s.poses.empty() || gate.due(s.poses.back(), log.laser_poses[k])) {
        s.poses.push_back(log.laser_poses[k]);
        s.scans.push_back(log.scans[k]);
      }
    s.full = TiledLogOddsGrid(s.options);
    for (std::size_t k = 0; k + 1 < s.scans.size(); ++k)
      s.full.integrate(s.poses[k], {}, s.scans[k]);
    std::fprintf(stderr, "%s: %zu scans, %zu pass the gate; the map has %zu tiles\n",
                 file.string().c_str(), log.scans.size(), s.scans.size(), s.full.tile_count());
    return s;
  }();
  return scene;
}

constexpr std::size_t kUpdateScans = 100;  // scans integrated by one MapUpdate iteration

void map_update_tiled(benchmark::State& state) {
  const GridScene& s = grid_scene();
  const std::size_t first = s.scans.size() - 1 - kUpdateScans;
  // The map of the scans before: a grid of its own (no tile shared), as after the first write
  // to each tile following a resampling.
  TiledLogOddsGrid grid(s.options);
  for (std::size_t k = 0; k < first; ++k) grid.integrate(s.poses[k], {}, s.scans[k]);
  for (auto _ : state)
    for (std::size_t k = first; k < first + kUpdateScans; ++k)
      grid.integrate(s.poses[k], {}, s.scans[k]);
  benchmark::DoNotOptimize(grid);
  state.counters["per_scan"] = benchmark::Counter(
      kUpdateScans, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void map_update_dense(benchmark::State& state) {
  const GridScene& s = grid_scene();
  const robot::OccupancyGrid extent = s.full.to_occupancy_grid();
  robot::LogOddsGrid grid(extent.width() + 2000, extent.height() + 2000, s.options.resolution,
                          extent.origin() - Vec<2>::Constant(50.0), s.options);
  const std::size_t first = s.scans.size() - 1 - kUpdateScans;
  for (auto _ : state)
    for (std::size_t k = first; k < first + kUpdateScans; ++k)
      grid.integrate(s.poses[k], {}, s.scans[k]);
  state.counters["per_scan"] = benchmark::Counter(
      kUpdateScans, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void copy_grids(benchmark::State& state) {
  const GridScene& s = grid_scene();
  const auto m = static_cast<std::size_t>(state.range(0));
  std::vector<TiledLogOddsGrid> particles(m, TiledLogOddsGrid(s.options));
  for (auto _ : state) {
    for (TiledLogOddsGrid& p : particles) p = s.full;
    benchmark::DoNotOptimize(particles.data());
  }
  state.counters["per_particle"] =
      benchmark::Counter(static_cast<double>(m), benchmark::Counter::kIsIterationInvariantRate |
                                                     benchmark::Counter::kInvert);
  state.counters["tiles"] = static_cast<double>(s.full.tile_count());
  state.counters["index_bytes"] = static_cast<double>(s.full.bytes().index);
}

void copy_on_write(benchmark::State& state) {
  const GridScene& s = grid_scene();
  const auto m = static_cast<std::size_t>(state.range(0));
  std::vector<TiledLogOddsGrid> particles(m, TiledLogOddsGrid(s.options));
  double copied = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    for (TiledLogOddsGrid& p : particles) p = s.full;
    state.ResumeTiming();
    for (TiledLogOddsGrid& p : particles) p.integrate(s.poses.back(), {}, s.scans.back());
    state.PauseTiming();
    copied = static_cast<double>(particles[0].unique_tile_count());
    state.ResumeTiming();
  }
  state.counters["per_particle"] =
      benchmark::Counter(static_cast<double>(m), benchmark::Counter::kIsIterationInvariantRate |
                                                     benchmark::Counter::kInvert);
  state.counters["tiles_copied"] = copied;
}

void memory(benchmark::State& state) {
  const GridScene& s = grid_scene();
  const auto m = static_cast<std::size_t>(state.range(0));
  const std::size_t scans = std::min<std::size_t>(60, s.scans.size());
  double per_particle = 0.0, alone = 0.0, dense = 0.0, distinct = 0.0;
  for (auto _ : state) {
    std::vector<TiledLogOddsGrid> particles(m, TiledLogOddsGrid(s.options));
    std::vector<TiledLogOddsGrid> next = particles;
    TiledLogOddsGrid one(s.options);
    for (std::size_t k = 0; k < scans; ++k) {
      for (std::size_t j = 0; j < m; ++j) {
        Rng rng({.seed = 3, .step = k, .index = j, .purpose = purpose::kData});
        const Vec<3> xi = rng.normal_vector<3>();  // one call: argument order is unspecified
        const Pose noise(0.05 * xi(0), 0.05 * xi(1), 0.02 * xi(2));
        particles[j].integrate(s.poses[k] + noise, {}, s.scans[k]);
      }
      one.integrate(s.poses[k], {}, s.scans[k]);
      Rng pick({.seed = 3, .step = k, .purpose = purpose::kResampling});
      for (std::size_t j = 0; j < m; ++j)
        next[j] = particles[std::min(m - 1, static_cast<std::size_t>(pick.uniform() * m))];
      std::swap(particles, next);
    }
    std::size_t index = 0;
    for (const TiledLogOddsGrid& p : particles) index += p.bytes().index;
    distinct = static_cast<double>(TiledLogOddsGrid::distinct_tiles(particles));
    per_particle =
        (static_cast<double>(index) + distinct * sizeof(TiledLogOddsGrid::Tile)) / double(m);
    alone = static_cast<double>(one.bytes().owned);
    const robot::OccupancyGrid extent = one.to_occupancy_grid();
    // LogOddsGrid: per cell a float of log-odds, a byte for "observed" and a byte of echoes.
    dense = 6.0 * extent.width() * extent.height();
  }
  state.counters["bytes_per_particle"] = per_particle;
  state.counters["one_map_bytes"] = alone;
  state.counters["dense_bytes"] = dense;
  state.counters["distinct_tiles"] = distinct;
}

// The tile size: the tiles one scan touches (what a particle copies per scan after a resampling)
// against the slots of the whole map's index (what every copy copies), for 16, 32 and 64 cells
// a side, counted from the cells each scan observes (every 10th gated scan).
void tile_size(benchmark::State& state) {
  const GridScene& s = grid_scene();
  std::array<double, 3> touched{};
  std::array<double, 3> slots{};
  const robot::OccupancyGrid whole = s.full.to_occupancy_grid();
  const double r = s.options.resolution;
  const auto corner = [&](const robot::OccupancyGrid& g) {
    return Eigen::Vector2i(static_cast<int>(std::lround(g.origin().x() / r)),
                           static_cast<int>(std::lround(g.origin().y() / r)));
  };
  for (auto _ : state) {
    std::size_t scans = 0;
    touched = {};
    for (std::size_t k = 0; k < s.scans.size(); k += 10, ++scans) {
      TiledLogOddsGrid one(s.options);
      one.integrate(s.poses[k], {}, s.scans[k]);
      const robot::OccupancyGrid g = one.to_occupancy_grid();
      const Eigen::Vector2i c = corner(g);
      for (int shift = 4; shift <= 6; ++shift) {
        std::set<std::pair<int, int>> tiles;
        for (int iy = 0; iy < g.height(); ++iy)
          for (int ix = 0; ix < g.width(); ++ix)
            if (g.at(ix, iy) != robot::OccupancyGrid::kUnknown)
              tiles.emplace((c.x() + ix) >> shift, (c.y() + iy) >> shift);
        touched[static_cast<std::size_t>(shift - 4)] += static_cast<double>(tiles.size());
      }
    }
    const Eigen::Vector2i c = corner(whole);
    for (int shift = 4; shift <= 6; ++shift) {
      touched[static_cast<std::size_t>(shift - 4)] /= static_cast<double>(scans);
      const double w = ((c.x() + whole.width() - 1) >> shift) - (c.x() >> shift) + 1;
      const double h = ((c.y() + whole.height() - 1) >> shift) - (c.y() >> shift) + 1;
      slots[static_cast<std::size_t>(shift - 4)] = w * h;
    }
  }
  for (int shift = 4; shift <= 6; ++shift) {
    const std::string side = std::to_string(1 << shift);
    const double cells = std::ldexp(1.0, 2 * shift);
    const auto i = static_cast<std::size_t>(shift - 4);
    // Per cell: a float of log-odds, a byte of echoes and a bit for "observed".
    state.counters["copied_bytes_per_scan_" + side] = touched[i] * (5.0 * cells + cells / 8.0);
    state.counters["index_bytes_" + side] = slots[i] * sizeof(std::shared_ptr<const void>);
  }
}

void scan_match(benchmark::State& state, bool derivatives) {
  const GridScene& s = grid_scene();
  const slam::GridScanModel model(s.full, slam::ScanMatchParams{});
  const slam::ScanMatchBeams beams = model.prepare(s.scans.back());
  const Pose x = s.poses.back();
  double value = 0.0;
  for (auto _ : state) {
    Vec<3> g = Vec<3>::Zero();
    robot::Mat3 h = robot::Mat3::Zero(), gn = robot::Mat3::Zero();
    value = derivatives ? model.negative_log_likelihood(beams, x, &g, &h, &gn)
                        : model.negative_log_likelihood(beams, x, nullptr, nullptr, nullptr);
    benchmark::DoNotOptimize(value);
    benchmark::DoNotOptimize(h);
  }
  state.counters["beams"] = static_cast<double>(beams.size());
}

void proposal(benchmark::State& state, slam::GridProposalKind kind) {
  const GridScene& s = grid_scene();
  const slam::GridScanModel model(s.full, slam::ScanMatchParams{});
  const slam::ScanMatchBeams beams = model.prepare(s.scans.back());
  const robot::OdometryAlphas alphas{0.05, 0.05, 0.05, 0.05};
  const robot::OdometryModel motion(alphas);
  const Pose previous = s.poses[s.poses.size() - 2];
  Rng data({.seed = 1, .purpose = purpose::kData});
  const robot::OdometryDelta u =
      robot::perturb_odometry(robot::between(previous, s.poses.back()), alphas, data);
  const slam::GridProposalInput in{&motion, u, &model, &beams};
  const auto p = slam::make_grid_proposal(kind);
  std::uint64_t j = 0;
  double evaluations = 0.0, calls = 0.0;
  for (auto _ : state) {
    Rng rng({.seed = 2, .index = j++, .purpose = purpose::kProposal});
    Pose next;
    slam::GridProposalStats st;
    benchmark::DoNotOptimize(p->propose(in, previous, rng, next, st));
    evaluations += st.evaluations;
    calls += 1.0;
  }
  state.counters["evaluations"] = evaluations / std::max(1.0, calls);
}

void grid_slam_log(benchmark::State& state, slam::GridProposalKind kind, int coarse) {
  const std::filesystem::path file =
      find_share_dir("data", "IMPLICIT_DATA_DIR") / "carmen" / "intel-corrected.log.gz";
  const robot::CarmenLog log = robot::read_carmen(file);
  slam::GridSlamRunOptions o;
  o.proposal = kind;
  o.implicit.coarse.coarse_smoothing = coarse;
  o.scan_match.coarse.coarse_smoothing = coarse;
  slam::GridSlamRun run;
  for (auto _ : state) run = slam::run_grid_slam(log, o);
  state.counters["relation_t_m"] = run.relations.translation_mean;
  state.counters["relation_r_deg"] = run.relations.rotation_mean_deg;
  state.counters["cpu_ms_per_scan"] = 1e3 * run.cpu_seconds / static_cast<double>(run.processed);
  state.counters["scans"] = static_cast<double>(run.processed);
  state.counters["ess_over_n"] = run.mean_ess;
  state.counters["evaluations"] = run.mean_evaluations;
  state.counters["fallbacks"] = static_cast<double>(run.fallbacks);
}

// The same over seeds 1..10 (filter and odometry noise): the mean and the standard deviation over
// the seeds of each run's mean relation errors, and the mean CPU per processed scan.
void grid_slam_seeds(benchmark::State& state, slam::GridProposalKind kind) {
  const std::filesystem::path file =
      find_share_dir("data", "IMPLICIT_DATA_DIR") / "carmen" / "intel-corrected.log.gz";
  const robot::CarmenLog log = robot::read_carmen(file);
  std::vector<double> t, r, cpu;
  for (auto _ : state) {
    t.clear();
    r.clear();
    cpu.clear();
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      slam::GridSlamRunOptions o;
      o.proposal = kind;
      o.filter.seed = seed;
      o.data_seed = seed;
      const slam::GridSlamRun run = slam::run_grid_slam(log, o);
      t.push_back(run.relations.translation_mean);
      r.push_back(run.relations.rotation_mean_deg);
      cpu.push_back(1e3 * run.cpu_seconds / static_cast<double>(run.processed));
    }
  }
  const auto mean = [](const std::vector<double>& v) {
    double sum = 0.0;
    for (double x : v) sum += x;
    return sum / static_cast<double>(v.size());
  };
  const auto sd = [&](const std::vector<double>& v) {
    const double m = mean(v);
    double sum = 0.0;
    for (double x : v) sum += (x - m) * (x - m);
    return std::sqrt(sum / static_cast<double>(v.size() - 1));
  };
  state.counters["relation_t_m"] = mean(t);
  state.counters["relation_t_sd"] = sd(t);
  state.counters["relation_r_deg"] = mean(r);
  state.counters["relation_r_sd"] = sd(r);
  state.counters["cpu_ms_per_scan"] = mean(cpu);
}

}  // namespace

BENCHMARK_CAPTURE(grid_slam_seeds, gmapping, slam::GridProposalKind::kScanMatch)
    ->Name("GridSlamSeeds/gmapping")
    ->Iterations(1)
    ->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(grid_slam_seeds, implicit, slam::GridProposalKind::kImplicit)
    ->Name("GridSlamSeeds/implicit")
    ->Iterations(1)
    ->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(grid_slam_seeds, bootstrap, slam::GridProposalKind::kBootstrap)
    ->Name("GridSlamSeeds/bootstrap")
    ->Iterations(1)
    ->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(scan_match, value, false)->Name("ScanMatch/value")->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(scan_match, derivatives, true)
    ->Name("ScanMatch/derivatives")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(proposal, bootstrap, slam::GridProposalKind::kBootstrap)
    ->Name("Proposal/bootstrap")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(proposal, gmapping, slam::GridProposalKind::kScanMatch)
    ->Name("Proposal/gmapping")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(proposal, implicit, slam::GridProposalKind::kImplicit)
    ->Name("Proposal/implicit")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(grid_slam_log, bootstrap, slam::GridProposalKind::kBootstrap, 0)
    ->Name("GridSlam/bootstrap")
    ->Iterations(1)
    ->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(grid_slam_log, gmapping, slam::GridProposalKind::kScanMatch, 0)
    ->Name("GridSlam/gmapping")
    ->Iterations(1)
    ->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(grid_slam_log, implicit, slam::GridProposalKind::kImplicit, 0)
    ->Name("GridSlam/implicit")
    ->Iterations(1)
    ->Unit(benchmark::kSecond);
BENCHMARK_CAPTURE(grid_slam_log, implicit_coarse, slam::GridProposalKind::kImplicit, 4)
    ->Name("GridSlam/implicit_coarse4")
    ->Iterations(1)
    ->Unit(benchmark::kSecond);
BENCHMARK(map_update_tiled)->Name("MapUpdate/tiled")->Unit(benchmark::kMillisecond);
BENCHMARK(map_update_dense)->Name("MapUpdate/dense")->Unit(benchmark::kMillisecond);
BENCHMARK(copy_grids)->Name("Copy")->Arg(30)->Arg(100)->Unit(benchmark::kMicrosecond);
BENCHMARK(copy_on_write)->Name("CopyOnWrite")->Arg(30)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK(tile_size)->Name("TileSize")->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(memory)->Name("Memory")->Arg(30)->Iterations(1)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
