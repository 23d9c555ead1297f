// `implicit eval`: scores an estimated trajectory against a reference (APE and RPE, as the evo
// package defines them) and against measured relative motions (the relation metric of Kümmerle
// et al. 2009). The definitions live in implicit/robot/trajectory_metrics.hpp; this file reads the
// flags and files and prints.
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "context.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/output_file.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/share_dir.hpp"
#include "implicit/robot/trajectory.hpp"
#include "implicit/robot/trajectory_metrics.hpp"
#include "registry.hpp"

namespace implicit::app {
namespace {

struct EvalCommand {
  std::string ref, est, relations;
  std::string format = "tum";
  std::string align = "none";
  double delta = 1.0;
  std::string delta_unit = "frames";
  bool all_pairs = false;
  double max_diff = 0.01;  ///< [s]
  double offset = 0.0;     ///< [s]
  std::string plot;        ///< the figure (.png, .pdf or .svg); empty: none
  RunContext ctx;
};

constexpr int kEvalResamples = 1000;
constexpr double kEvalLevel = 0.95;

/// A library error in front of which flag (or file) it came from; the type, and so the exit code
/// (1), kept.
template <typename F>
auto eval_naming(const std::string& what, F&& f) {
  try {
    return f();
  } catch (const ParseError& e) {
    throw ParseError(fmt::format("eval {}: {}", what, e.what()));
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(fmt::format("eval {}: {}", what, e.what()));
  }
}

robot::Trajectory eval_read(const std::string& flag, const std::string& file,
                            const std::string& format) {
  return eval_naming(
      flag, [&] { return format == "kitti" ? robot::read_kitti(file) : robot::read_tum(file); });
}

nlohmann::json eval_stats_json(const robot::ErrorStatistics& s) {
  return {{"count", s.count},
          {"mean", s.mean},
          {"median", s.median},
          {"rmse", s.rmse},
          {"max", s.max},
          {"min", s.min},
          {"std", s.std},
          {"mean_ci", {s.mean_lo, s.mean_hi}},
          {"rmse_ci", {s.rmse_lo, s.rmse_hi}}};
}

/// The statistics of each named error column, in order: (name, statistics).
using EvalRows = std::vector<std::pair<std::string, robot::ErrorStatistics>>;

EvalRows eval_rows(const std::string& prefix, const robot::TrajectoryErrors& e,
                   const robot::StatisticsOptions& o) {
  return {{prefix + " translation [m]", robot::error_statistics(e.translation, o)},
          {prefix + " rotation [deg]", robot::error_statistics(e.rotation_deg, o)},
          {prefix + " full |E - I|", robot::error_statistics(e.full, o)}};
}

void eval_print_table(const EvalRows& rows) {
  fmt::print("{:<26}{:>11}{:>11}{:>11}{:>11}{:>11}{:>11}  {:<23}{}\n", "", "mean", "median", "rmse",
             "max", "min", "std", "mean 95% CI", "rmse 95% CI");
  for (const auto& [name, s] : rows)
    fmt::print("{:<26}{:>11.5g}{:>11.5g}{:>11.5g}{:>11.5g}{:>11.5g}{:>11.5g}  {:<23}{}\n", name,
               s.mean, s.median, s.rmse, s.max, s.min, s.std,
               fmt::format("[{:.5g}, {:.5g}]", s.mean_lo, s.mean_hi),
               fmt::format("[{:.5g}, {:.5g}]", s.rmse_lo, s.rmse_hi));
}

void eval_write_csv(const RunContext& ctx, const std::string& name, const std::string& header,
                    const robot::PosePairs& pairs, const robot::TrajectoryErrors& e) {
  OutputFile out(ctx.csv_path(name));
  out.stream() << header << "\n";
  for (std::size_t k = 0; k < e.translation.size(); ++k)
    out.stream() << fmt::format("{},{},{},{},{}\n", pairs.times[e.first[k]],
                                pairs.times[e.second[k]], e.translation[k], e.rotation_deg[k],
                                e.full[k]);
  out.commit();
}

// ---- --plot: python/plots/eval_plot.py draws what this command computed ------------------------

/// The check of --plot, before any work: a name ending in .png, .pdf or .svg (matplotlib writes
/// the format the name says) in a folder that exists.
CLI::Validator eval_plot_validator() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text.empty()) return "expected a file name, got an empty one";
        const std::filesystem::path file(text);
        const std::string ext = file.extension().string();
        if (ext != ".png" && ext != ".pdf" && ext != ".svg")
          return "expected a name ending in .png, .pdf or .svg, got '" + text + "'";
        std::error_code ec;
        if (!file.parent_path().empty() && !std::filesystem::is_directory(file.parent_path(), ec))
          return "expected a file in an existing folder, got '" + text + "' (no folder '" +
                 file.parent_path().string() + "')";
        return {};
      },
      "FILE.png|.pdf|.svg");
}

/// The plot's data, one row per pose pair: the reference position, the aligned estimate, the APE
/// translation error and the distance along the reference (eval_plot.py's columns).
std::string eval_plot_csv(const robot::PosePairs& pairs, const robot::Alignment& alignment,
                          const robot::TrajectoryErrors& ape) {
  std::string out = "t_s,ref_x_m,ref_y_m,est_x_m,est_y_m,ape_translation_m,path_m\n";
  double path = 0.0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (k > 0) path += (pairs.ref[k].translation - pairs.ref[k - 1].translation).norm();
    const Vec<3> e = alignment.apply(pairs.est[k]).translation;
    out += fmt::format("{},{},{},{},{},{},{}\n", pairs.times[k], pairs.ref[k].translation(0),
                       pairs.ref[k].translation(1), e(0), e(1), ape.translation[k], path);
  }
  return out;
}

/// The last `lines` lines of a file (a script's messages), joined by " | ".
std::string eval_plot_tail(const std::filesystem::path& file, std::size_t lines) {
  std::ifstream in(file);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) all.push_back(line);
  std::string out;
  for (std::size_t k = all.size() > lines ? all.size() - lines : 0; k < all.size(); ++k)
    out += (out.empty() ? "" : " | ") + all[k];
  return out;
}

/// Draws the figure into `file` through the plot script ($IMPLICIT_PYTHON, else /usr/bin/python3,
/// as `implicit reproduce` runs its figures): the script writes a temporary name beside `file`,
/// renamed over it when it succeeded, so a failed or stopped script leaves no half-drawn figure.
/// Throws InvalidArgument naming --plot and the script's last words when it fails (exit 1).
void eval_draw_plot(const std::string& file, const std::string& csv, const std::string& title) {
  const std::filesystem::path script =
      eval_naming("--plot", [] { return find_share_dir("plots", "IMPLICIT_PLOTS_DIR"); }) /
      "eval_plot.py";
  require(std::filesystem::exists(script), "eval --plot {}: plot script {} not found", file,
          script.string());
  const char* python_env = std::getenv("IMPLICIT_PYTHON");
  const std::string python = python_env && *python_env ? python_env : "/usr/bin/python3";
  const std::filesystem::path target(file);
  const std::filesystem::path work =
      std::filesystem::temp_directory_path() / fmt::format("implicit_eval_plot_{}", ::getpid());
  std::filesystem::create_directories(work);
  struct RemoveWork {
    std::filesystem::path dir;
    ~RemoveWork() {
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    }
  } remove_work{work};
  const std::filesystem::path data = work / "eval_plot.csv", log = work / "eval_plot.log";
  std::ofstream(data) << csv;
  std::filesystem::path partial = target;
  partial.replace_extension(fmt::format("tmp{}{}", ::getpid(), target.extension().string()));
  const UnfinishedOutput drawing(partial);
  setenv("MPLBACKEND", "Agg", 0);  // no display needed
  const int code =
      run_child_process({python, script.string(), data.string(), partial.string(), title}, log);
  std::error_code ec;
  if (code == 0 && std::filesystem::exists(partial)) {
    std::filesystem::rename(partial, target, ec);
    require(!ec, "eval --plot {}: expected a writable file, got {}", file, ec.message());
    return;
  }
  std::filesystem::remove(partial, ec);
  throw InvalidArgument(
      fmt::format("eval --plot {}: {} exited with code {}{}: {}", file, script.filename().string(),
                  code, code == 3 ? " (matplotlib missing)" : "", eval_plot_tail(log, 3)));
}

void run_eval(const EvalCommand& c) {
  if (c.ref.empty() && c.relations.empty())
    throw CLI::ValidationError("--ref", "expected --ref FILE (or --relations FILE), got neither");
  if (c.ref.empty() && c.align != "none")
    throw CLI::ValidationError("--align", "expected --ref FILE to align with, got none");
  if (c.ref.empty() && !c.plot.empty())
    throw CLI::ValidationError("--plot",
                               "expected --ref FILE to draw the estimate against, got none");
  if (c.delta_unit == "frames" && c.delta != std::floor(c.delta))
    throw CLI::ValidationError(
        "--delta", fmt::format("expected an integer number of frames, got {}", c.delta));
  const ThreadLimit threads(c.ctx.threads);  // the bootstrap resamples run in parallel
  const robot::TimeAssociationOptions assoc{.max_diff = c.max_diff, .offset = c.offset};
  const robot::StatisticsOptions stats{
      .seed = c.ctx.seed, .resamples = kEvalResamples, .level = kEvalLevel};
  const robot::Trajectory est = eval_read("--est", c.est, c.format);
  nlohmann::json j{
      {"est", c.est},
      {"est_poses", est.size()},
      {"format", c.format},
      {"max_diff", c.max_diff},
      {"offset", c.offset},
      {"bootstrap", {{"resamples", kEvalResamples}, {"level", kEvalLevel}, {"seed", c.ctx.seed}}}};
  EvalRows rows;
  std::string head = fmt::format("eval: {} ({}, {} poses)", c.est, c.format, est.size());
  if (!c.ref.empty()) {
    const robot::Trajectory ref = eval_read("--ref", c.ref, c.format);
    const auto pairs = eval_naming("--ref/--est (raise --max-diff or set --offset?)",
                                   [&] { return robot::associate(ref, est, assoc); });
    const auto kind = robot::alignment_kind_from_string(c.align);
    const auto alignment =
        eval_naming("--align " + c.align, [&] { return robot::align_umeyama(pairs, kind); });
    const auto ape = robot::absolute_pose_error(pairs, alignment);
    const robot::RpeOptions rpe_options{
        .delta = c.delta,
        .unit = c.delta_unit == "m" ? robot::DeltaUnit::kMetres : robot::DeltaUnit::kFrames,
        .all_pairs = c.all_pairs};
    const auto rpe = eval_naming(
        "--delta", [&] { return robot::relative_pose_error(pairs, alignment, rpe_options); });
    rows = eval_rows("APE", ape, stats);
    const EvalRows rpe_rows = eval_rows("RPE", rpe, stats);
    rows.insert(rows.end(), rpe_rows.begin(), rpe_rows.end());
    const Eigen::Matrix3d& r = alignment.rotation;
    j["ref"] = c.ref;
    j["ref_poses"] = ref.size();
    j["pairs"] = pairs.size();
    j["alignment"] = {
        {"kind", c.align},
        {"rotation",
         {{r(0, 0), r(0, 1), r(0, 2)}, {r(1, 0), r(1, 1), r(1, 2)}, {r(2, 0), r(2, 1), r(2, 2)}}},
        {"rotation_deg", alignment.rotation_angle() * 180.0 / kPi},
        {"translation",
         {alignment.translation(0), alignment.translation(1), alignment.translation(2)}},
        {"scale", alignment.scale}};
    j["ape"] = {{"translation_m", eval_stats_json(rows[0].second)},
                {"rotation_deg", eval_stats_json(rows[1].second)},
                {"full", eval_stats_json(rows[2].second)}};
    j["rpe"] = {{"delta", c.delta},
                {"delta_unit", c.delta_unit},
                {"all_pairs", c.all_pairs},
                {"pairs", rpe.translation.size()},
                {"translation_m", eval_stats_json(rows[3].second)},
                {"rotation_deg", eval_stats_json(rows[4].second)},
                {"full", eval_stats_json(rows[5].second)}};
    if (!c.plot.empty()) {
      eval_draw_plot(c.plot, eval_plot_csv(pairs, alignment, ape),
                     fmt::format("{} against {}, alignment {}",
                                 std::filesystem::path(c.est).filename().string(),
                                 std::filesystem::path(c.ref).filename().string(), c.align));
      j["plot"] = c.plot;
    }
    if (!c.ctx.out_dir.empty()) {
      eval_naming("--out", [&] {
        eval_write_csv(c.ctx, "ape.csv", "t,t,translation_m,rotation_deg,full", pairs, ape);
        eval_write_csv(c.ctx, "rpe.csv", "t_i,t_j,translation_m,rotation_deg,full", pairs, rpe);
        return 0;
      });
    }
    head += fmt::format(
        " against {} ({} poses): {} pose pairs within {} s (offset {} s); alignment {}: "
        "rotation {:.4g} deg, translation ({:.4g}, {:.4g}, {:.4g}) m, scale {:.6g}; RPE over "
        "{} pairs {} {} apart{}",
        c.ref, ref.size(), pairs.size(), c.max_diff, c.offset, c.align,
        alignment.rotation_angle() * 180.0 / kPi, alignment.translation(0),
        alignment.translation(1), alignment.translation(2), alignment.scale, rpe.translation.size(),
        c.delta, c.delta_unit, c.all_pairs ? " (all pairs)" : "");
  }
  std::optional<robot::RelationErrors> rel;
  if (!c.relations.empty()) {
    const auto relations =
        eval_naming("--relations", [&] { return robot::read_relations(c.relations); });
    rel = eval_naming("--relations " + c.relations,
                      [&] { return robot::relation_errors(est, relations, assoc); });
    const auto t = robot::error_statistics(rel->translation, stats);
    const auto a = robot::error_statistics(rel->rotation_deg, stats);
    rows.emplace_back("relations translation [m]", t);
    rows.emplace_back("relations rotation [deg]", a);
    j["relations"] = {{"file", c.relations},
                      {"relations", relations.size()},
                      {"used", rel->used.size()},
                      {"skipped", rel->skipped},
                      {"translation_m", eval_stats_json(t)},
                      {"rotation_deg", eval_stats_json(a)},
                      {"translation_sq_mean_m2", rel->translation_sq_mean},
                      {"rotation_sq_mean_deg2", rel->rotation_sq_mean_deg}};
  }
  if (c.ctx.json) {
    print_json(j);
    return;
  }
  fmt::print("{}\n", head);
  eval_print_table(rows);
  if (rel)
    fmt::print(
        "relation metric ({}: {} used, {} without poses): translation {:.5g} m (squared {:.5g} "
        "m^2), rotation {:.5g} deg (squared {:.5g} deg^2)\n",
        c.relations, rel->used.size(), rel->skipped, rel->translation_mean,
        rel->translation_sq_mean, rel->rotation_mean_deg, rel->rotation_sq_mean_deg);
}

void setup_eval(CLI::App& sub) {
  auto cmd = std::make_shared<EvalCommand>();
  sub.add_option("--ref", cmd->ref, "Reference trajectory FILE (ground truth)");
  sub.add_option("--est", cmd->est, "Estimated trajectory FILE")->required();
  sub.add_option("--format", cmd->format,
                 "File format of --ref and --est: tum (t x y z qx qy qz qw) or kitti (3x4 "
                 "matrices, time = frame index)")
      ->check(CLI::IsMember({"tum", "kitti"}))
      ->capture_default_str();
  sub.add_option("--align", cmd->align,
                 "Least-squares alignment of the estimate onto the reference before scoring "
                 "(Umeyama): none, se2 (turn about z), se3 or sim3 (with scale)")
      ->check(CLI::IsMember({"none", "se2", "se3", "sim3"}))
      ->capture_default_str();
  sub.add_option("--delta", cmd->delta, "RPE: distance between the poses of a pair")
      ->check(in_range(1e-6, 1e9))
      ->capture_default_str();
  sub.add_option("--delta-unit", cmd->delta_unit,
                 "RPE: --delta in frames (associated poses) or m (path length of the reference)")
      ->check(CLI::IsMember({"frames", "m"}))
      ->capture_default_str();
  sub.add_flag("--all-pairs", cmd->all_pairs,
               "RPE: a pair from every pose (default: pairs that do not overlap, as evo)");
  sub.add_option("--max-diff", cmd->max_diff,
                 "[s] largest time difference of an associated pose pair")
      ->check(in_range(0.0, 1e9))
      ->capture_default_str();
  sub.add_option("--offset", cmd->offset, "[s] added to the estimate's times before association")
      ->check(in_range(-1e12, 1e12))
      ->capture_default_str();
  sub.add_option(
      "--relations", cmd->relations,
      "Relations FILE (t1 t2 x y z roll pitch yaw): the relation metric of the estimate");
  sub.add_option("--plot", cmd->plot,
                 "Draw the reference and the aligned estimate from above and the APE translation "
                 "error along the path into FILE (.png, .pdf or .svg; python3 with matplotlib)")
      ->check(eval_plot_validator());
  add_common_options(sub, cmd->ctx);
  sub.get_option("--out")->description(
      "Folder for ape.csv and rpe.csv (the error of every pose pair)");
  sub.get_option("--seed")->description("Seed of the bootstrap intervals");
  set_examples(sub,
               {"implicit eval --ref truth.tum --est estimate.tum --align se3",
                "implicit eval --ref 00.txt --est 00_est.txt --format kitti --align sim3 "
                "--delta 100 --delta-unit m --json",
                "implicit eval --est estimate.tum --relations intel.relations",
                "implicit eval --ref truth.tum --est estimate.tum --align se2 --plot eval.png"});
  sub.callback([cmd] { run_eval(*cmd); });
}

const Registrar register_eval{
    "eval", "Score a trajectory: APE, RPE (evo's definitions) and the relation metric", setup_eval};

}  // namespace
}  // namespace implicit::app
