// `implicit reproduce`: every experiment of the paper in one run, with the report of
// apps/report.hpp (the paper's Tables 2, 4, 5, 6 and Figures 1, 2, 4, 5, 6, 7, side by side).
//
// Each configuration runs in-process and in its own try/catch: a failing experiment is marked
// failed in results.json and the report, and the others still run. Figures are drawn by
// python/plots/figureN.py from the CSV files the experiments write; a missing or failing script
// marks that figure failed without stopping the report.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "context.hpp"
#include "experiments.hpp"
#include "experiments/parallel_runs.hpp"
#include "implicit/build_info.hpp"
#include "implicit/core/error.hpp"
#include "implicit/core/parallel.hpp"
#include "implicit/core/share_dir.hpp"
#include "registry.hpp"
#include "report.hpp"
#include "reproduce_plan.hpp"
#include "results_file.hpp"

namespace implicit::app {
namespace {

using nlohmann::json;

const std::vector<std::string> kExperiments = {
    "slit",      "arm",       "himmelblau", "mcl", "slam", "proposal_gain", "global_localization",
    "laser_mcl", "grid_slam", "da"};

struct ReproduceOptions {
  bool quick = false;
  bool report_only = false;
  bool no_figures = false;
  std::vector<std::string> only;
};

// ---- Machine and build -----------------------------------------------------------------------

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) {
        auto s = line.substr(colon + 1);
        s.erase(0, s.find_first_not_of(" \t"));
        return s;
      }
    }
  return "unknown";
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

std::string folder_name(const std::string& label) {
  std::string out;
  for (char c : label) {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.')
      out += c;
    else if (c == '=')
      continue;
    else if (!out.empty() && out.back() != '_')
      out += '_';
  }
  return out;
}

// Atomic (OutputFile): a killed run leaves the previous file, not a half-written one.
void write_text(const std::filesystem::path& file, const std::string& text) {
  write_output_file(file, text);
}

std::string tail(const std::filesystem::path& file, std::size_t lines) {
  std::ifstream in(file);
  std::vector<std::string> all;
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) all.push_back(line);
  std::string out;
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i)
    out += (out.empty() ? "" : " / ") + all[i];
  return out;
}

// ---- Figures ----------------------------------------------------------------------------------

/// Each sweep configuration writes its one-row summary (`mcl_summary.csv`, `slam_summary.csv`)
/// into its own folder under DIR/runs; the CPU-time-vs-error panels need every configuration, so
/// the rows of this run's configurations (named in `results`) are gathered into DIR/<name>, after
/// the figure configuration's own rows. Identical rows are kept once, so running this again
/// (e.g. with --report-only) changes nothing. Returns the number of data rows written.
std::size_t gather_summaries(const json& results, const std::filesystem::path& dir,
                             const std::string& name) {
  std::vector<std::filesystem::path> files;
  if (std::filesystem::exists(dir / name)) files.push_back(dir / name);
  if (results.contains("experiments"))
    for (const auto& [experiment, e] : results["experiments"].items())
      for (const auto& run : e.value("runs", json::array())) {
        const auto f = dir / "runs" / folder_name(run.value("label", std::string())) / name;
        if (run.value("status", std::string()) == "ok" && std::filesystem::exists(f))
          files.push_back(f);
      }
  std::string header;
  std::vector<std::string> rows;
  for (const auto& f : files) {
    std::ifstream in(f);
    std::string line;
    if (!std::getline(in, line)) continue;
    if (header.empty()) header = line;
    if (line != header) continue;  // a summary from another version of the program: leave it out
    while (std::getline(in, line))
      if (!line.empty() && std::find(rows.begin(), rows.end(), line) == rows.end())
        rows.push_back(line);
  }
  if (header.empty()) return 0;
  std::string text = header + "\n";
  for (const auto& r : rows) text += r + "\n";
  write_text(dir / name, text);
  return rows.size();
}

struct FigureSpec {
  int number;
  std::string experiment;
};
const std::vector<FigureSpec> kFigures = {{1, "slit"},
                                          {2, "slit"},
                                          {4, "arm"},
                                          {5, "himmelblau"},
                                          {6, "mcl"},
                                          {7, "slam"},
                                          {8, "proposal_gain"},
                                          {9, "global_localization"},
                                          {10, "laser_mcl"},
                                          {11, "grid_slam"},
                                          {12, "da"}};

// The plot scripts: $IMPLICIT_PLOTS_DIR, else <prefix>/share/implicit/plots of the install (or the
// build tree's link to python/plots). Empty, with the reason in `error`, when there are none: the
// experiments' numbers still count, and each figure says why it is missing.
std::filesystem::path plots_dir(std::string& error) {
  try {
    return find_share_dir("plots", "IMPLICIT_PLOTS_DIR");
  } catch (const InvalidArgument& e) {
    error = e.what();
    return {};
  }
}

json draw_figures(const json& results, const std::filesystem::path& dir, bool no_figures,
                  bool show) {
  json figures = json::object();
  const char* python_env = std::getenv("IMPLICIT_PYTHON");
  const std::string python = python_env && *python_env ? python_env : "/usr/bin/python3";
  setenv("MPLBACKEND", "Agg", 0);  // no display needed
  const auto logs = dir / "logs";
  std::string no_scripts;
  const auto scripts = no_figures ? std::filesystem::path() : plots_dir(no_scripts);
  for (const auto& f : kFigures) {
    const std::string key = fmt::format("figure{}", f.number);
    const auto script = scripts / (key + ".py");
    json entry = {{"experiment", f.experiment}, {"script", script.string()}};
    std::string exp_status = "skipped";
    if (results.contains("experiments") && results["experiments"].contains(f.experiment))
      exp_status = results["experiments"][f.experiment].value("status", exp_status);
    if (no_figures || exp_status == "skipped") {
      entry["status"] = "skipped";
      entry["error"] = no_figures ? "--no-figures" : "experiment not selected (--only)";
    } else if (exp_status == "failed") {
      entry["status"] = "failed";
      entry["error"] = fmt::format("experiment {} failed", f.experiment);
    } else if (!no_scripts.empty()) {
      entry["status"] = "failed";
      entry["error"] = no_scripts;
    } else if (!std::filesystem::exists(script)) {
      entry["status"] = "failed";
      entry["error"] = fmt::format("plot script {} not found", script.string());
    } else {
      std::filesystem::create_directories(logs);
      const auto log = logs / (key + ".log");
      const auto png = dir / (key + ".png");
      const auto svg = dir / (key + ".svg");
      std::filesystem::remove(png);
      std::filesystem::remove(svg);
      if (show) fmt::print(stderr, "reproduce: drawing {}\n", key);
      const auto start = std::chrono::steady_clock::now();
      // Stopped with this program (run_child_process): a SIGINT or SIGTERM stops the script and
      // removes its half-drawn figure, so nothing writes into DIR after the command ended.
      const UnfinishedOutput drawing_png(png), drawing_svg(svg);
      const int code = run_child_process({python, script.string(), dir.string()}, log);
      entry["seconds"] =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      entry["log"] = (std::filesystem::path("logs") / (key + ".log")).string();
      if (code != 0) {
        entry["status"] = "failed";
        entry["error"] = fmt::format("{} exited with code {}: {}", script.filename().string(), code,
                                     tail(log, 3));
      } else if (!std::filesystem::exists(png)) {
        entry["status"] = "failed";
        entry["error"] =
            fmt::format("{} did not write {}", script.filename().string(), png.filename().string());
      } else {
        entry["status"] = "ok";
        json files = {png.filename().string()};
        if (std::filesystem::exists(svg)) files.push_back(svg.filename().string());
        entry["files"] = files;
      }
    }
    figures[key] = entry;
  }
  return figures;
}

// ---- The files of a run ------------------------------------------------------------------------

/// The files of this run in DIR, relative to it, sorted: every output written through OutputFile
/// into DIR, the figures, and (with --report-only) the files the earlier run listed that still
/// exist. results.json lists them under "files" with the run's "run_id" (docs/reproducing.md).
json files_of_run(const json& results, const std::filesystem::path& dir) {
  std::set<std::string> names;
  auto add = [&](const std::filesystem::path& file) {
    const auto relative = file.lexically_relative(dir);
    if (!relative.empty() && *relative.begin() != "..") names.insert(relative.generic_string());
  };
  for (const auto& file : committed_output_paths()) add(file);
  if (results.contains("files") && results["files"].is_array())
    for (const auto& f : results["files"])
      if (f.is_string() && std::filesystem::exists(dir / f.get<std::string>()))
        add(dir / f.get<std::string>());
  for (const auto& [key, figure] : results["figures"].items()) {
    for (const auto& f : figure.value("files", json::array())) add(dir / f.get<std::string>());
    if (figure.contains("log")) add(dir / figure["log"].get<std::string>());
  }
  for (const char* name : {"results.json", "report.md", "report.html"}) add(dir / name);
  return json(std::vector<std::string>(names.begin(), names.end()));
}

/// Removes what an earlier run wrote into `dir`: the files its results.json lists (relative
/// names inside DIR only, nothing else of the folder) and results.json and the reports, which
/// would otherwise describe files this run is about to replace. An earlier run killed before it
/// wrote results.json leaves files no results.json lists: those of the new run are listed.
void remove_earlier_run(const std::filesystem::path& dir) {
  const auto file = dir / "results.json";
  std::vector<std::string> listed;
  try {
    const json earlier = read_results(file);
    for (const auto& f : earlier.value("files", json::array()))
      if (f.is_string()) listed.push_back(f.get<std::string>());
  } catch (const std::exception&) {
    // No earlier run, or not one of ours: nothing of it is removed.
  }
  for (const char* name : {"results.json", "report.md", "report.html"}) listed.emplace_back(name);
  for (const auto& name : listed) {
    const std::filesystem::path relative(name);
    const bool inside = relative.is_relative() && !relative.empty() &&
                        std::none_of(relative.begin(), relative.end(),
                                     [](const auto& part) { return part == ".."; });
    std::error_code ec;
    if (inside && std::filesystem::is_regular_file(dir / relative, ec))
      std::filesystem::remove(dir / relative, ec);
  }
}

// ---- The run -----------------------------------------------------------------------------------

json run_plan(const Plan& plan, const RunContext& ctx, const ReproduceOptions& opt) {
  json experiments = json::object();
  for (const auto& e : kExperiments)
    experiments[e] = {{"status", "skipped"}, {"seconds", 0.0}, {"runs", json::array()}};
  // Weights in milli-units so that Progress's integer counter can carry them.
  auto units = [](const Config& c) {
    return std::max<std::size_t>(1, static_cast<std::size_t>(c.weight * 1000.0));
  };
  std::size_t total_units = 0;
  for (const auto& c : plan.configs) total_units += units(c);
  Progress overall("reproduce", total_units, ctx.show_progress(), Progress::Style::kLines);
  if (ctx.show_progress() && !plan.configs.empty())
    fmt::print(stderr, "reproduce: {} configurations ({} settings); first: {}\n",
               plan.configs.size(), opt.quick ? "quick" : "full", plan.configs.front().label);
  // Summaries are appended by each run: start this run's from empty, so that rows of an earlier
  // run into the same folder never reach the figures.
  for (const auto& c : plan.configs) {
    if (c.writes_figures)
      std::filesystem::remove(ctx.out_dir / fmt::format("{}_summary.csv", c.experiment));
    else
      std::filesystem::remove_all(ctx.out_dir / "runs" / folder_name(c.label));
  }
  for (std::size_t i = 0; i < plan.configs.size(); ++i) {
    const auto& c = plan.configs[i];
    RunContext run_ctx = ctx;
    run_ctx.out_dir = c.writes_figures ? ctx.out_dir : ctx.out_dir / "runs" / folder_name(c.label);
    json entry = {{"label", c.label}, {"settings", c.settings}};
    const auto start = std::chrono::steady_clock::now();
    try {
      entry["result"] = c.run(run_ctx);
      entry["status"] = "ok";
    } catch (const std::exception& e) {
      entry["status"] = "failed";
      entry["error"] = e.what();
    } catch (...) {
      entry["status"] = "failed";
      entry["error"] = "unknown exception";
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    entry["seconds"] = seconds;
    if (ctx.show_progress() && entry["status"] == "failed")
      fmt::print(stderr, "reproduce: {} failed: {}\n", c.label, entry["error"].get<std::string>());
    auto& e = experiments[c.experiment];
    e["runs"].push_back(entry);
    e["seconds"] = e["seconds"].get<double>() + seconds;
    overall.tick(units(c), i + 1 < plan.configs.size() ? plan.configs[i + 1].label : "report");
  }
  overall.finish();
  for (auto& [name, e] : experiments.items()) {
    if (e["runs"].empty()) continue;
    std::size_t good = 0;
    for (const auto& r : e["runs"]) good += r["status"] == "ok";
    e["status"] = good == e["runs"].size() ? "ok" : good == 0 ? "failed" : "partial";
    e["configurations"] = e["runs"].size();
    e["failed"] = e["runs"].size() - good;
  }
  return experiments;
}

std::string command_line(const RunContext& ctx, const ReproduceOptions& opt) {
  std::string s =
      fmt::format("implicit reproduce --out {} --seed {}", ctx.out_dir.string(), ctx.seed);
  if (ctx.threads > 0) s += fmt::format(" --threads {}", ctx.threads);
  if (opt.quick) s += " --quick";
  if (!opt.only.empty()) {
    s += " --only ";
    for (std::size_t i = 0; i < opt.only.size(); ++i) s += (i ? "," : "") + opt.only[i];
  }
  return s;
}

/// Writes results.json, the table CSVs, the figures and the report; returns the exit code.
int finish(json& results, const RunContext& ctx, const ReproduceOptions& opt,
           const std::filesystem::path& source) {
  const auto& dir = ctx.out_dir;
  // Tables and a first results.json before the plot scripts, which may read both.
  results["tables"] = report::write_table_csvs(results, dir, source);
  results["figures"] = json::object();
  write_text(dir / "results.json", results.dump(2) + "\n");
  gather_summaries(results, dir, "mcl_summary.csv");
  gather_summaries(results, dir, "slam_summary.csv");
  // Under MPI only rank 0's figures are kept (experiments/parallel_runs.hpp): the others draw none.
  results["figures"] = draw_figures(results, dir, opt.no_figures || experiments::rank_index() != 0,
                                    ctx.show_progress());
  results["files"] = files_of_run(results, dir);
  write_text(dir / "results.json", results.dump(2) + "\n");
  const auto doc = report::build_report(results, dir);
  write_text(dir / "report.md", doc.markdown());
  write_text(dir / "report.html", doc.html(doc.title()));

  bool all_ok = true;
  for (const auto& [name, e] : results["experiments"].items())
    if (e["status"] != "ok" && e["status"] != "skipped") all_ok = false;
  for (const auto& [name, f] : results["figures"].items())
    if (f["status"] == "failed") all_ok = false;

  if (ctx.json) {
    fmt::print("{}\n", results.dump(2));
  } else if (!ctx.quiet) {
    fmt::print("Report: {} and {}\n", (dir / "report.html").string(), (dir / "report.md").string());
    // One table, its columns as wide as their longest cell (global_localization is 19
    // characters); the figures in their numbers' order (the JSON object sorts figure10 first).
    std::vector<std::vector<std::string>> rows;
    for (const auto& name : kExperiments) {
      const auto& e = results["experiments"][name];
      if (!e.is_object()) continue;
      rows.push_back({name, e["status"].get<std::string>(),
                      fmt::format("{:.1f} s", e["seconds"].get<double>())});
    }
    for (const auto& f : kFigures) {
      const std::string key = fmt::format("figure{}", f.number);
      if (results["figures"].contains(key))
        rows.push_back({key, results["figures"][key]["status"].get<std::string>()});
    }
    fmt::print("{}", report::aligned_columns(rows, {false, false, true}));
  }
  return all_ok ? 0 : 3;
}

int reproduce(RunContext ctx, const ReproduceOptions& opt) {
  ctx.out_dir = std::filesystem::absolute(ctx.out_dir);
  json results;
  if (opt.report_only) {
    // Read before the folder is made: a refused --report-only leaves nothing behind.
    const auto file = ctx.out_dir / "results.json";
    results = read_results(file);
    create_out_dir(ctx.out_dir);
    try {
      return finish(results, ctx, opt, file);
    } catch (const json::exception& e) {
      // A wrongly typed value: the library's message alone does not say which file.
      throw ParseError(fmt::format("{}: unexpected content ({})", file.string(), e.what()));
    }
  }
  create_out_dir(ctx.out_dir);
  const auto start = std::chrono::steady_clock::now();
  // Before anything is written: an earlier run's files go, so that DIR never mixes two runs.
  remove_earlier_run(ctx.out_dir);
  ThreadLimit limit(ctx.threads);
  const Plan plan = make_plan(opt.quick, opt.only);
  results["schema"] = "implicit-reproduce-1";
  results["version"] = build_info::version;
  results["commit"] = build_info::commit;
  results["compiler"] = build_info::compiler;
  results["build_type"] = build_info::build_type;
  results["cxx_flags"] = build_info::cxx_flags;
  results["cpu_model"] = cpu_model();
  results["hardware_threads"] = std::thread::hardware_concurrency();
  results["threads"] = active_threads();
  results["seed"] = ctx.seed;
  results["quick"] = opt.quick;
  results["only"] = opt.only;
  results["command"] = command_line(ctx, opt);
  results["started_utc"] = utc_now();
  results["run_id"] = fmt::format("{}-{}", results["started_utc"].get<std::string>(), ::getpid());
  results["settings"] = plan.settings;
  results["paper"] = report::paper_numbers();
  results["reference"] = report::reference_numbers();
  report::report_text();  // a bad text file stops here, not after the runs
  results["experiments"] = run_plan(plan, ctx, opt);
  results["seconds_total"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return finish(results, ctx, opt, ctx.out_dir / "results.json");
}

Registrar register_reproduce{
    "reproduce",
    "Every table and figure of the paper, side by side with ours: DIR/report.html, report.md, "
    "results.json",
    [](CLI::App& sub) {
      static RunContext ctx;
      static ReproduceOptions opt;
      ctx.out_dir = "out";
      add_common_options(sub, ctx);
      sub.add_flag("--quick", opt.quick,
                   "Reduced runs (about 15 seconds instead of 5 minutes); the report says which");
      sub.add_option("--only", opt.only, "Run a subset of the experiments (comma-separated)")
          ->delimiter(',')
          ->check(CLI::IsMember(kExperiments));
      sub.add_flag("--report-only", opt.report_only,
                   "Rebuild the report and figures from DIR/results.json without running");
      sub.add_flag("--no-figures", opt.no_figures, "Do not run the plot scripts");
      set_examples(sub, {"implicit reproduce                       # full settings into out/",
                         "implicit reproduce --quick --out /tmp/r  # about 15 seconds",
                         "implicit reproduce --only slit,arm --threads 2 --seed 7",
                         "implicit reproduce --report-only --out out  # redraw from results.json"});
      sub.callback([] {
        const int code = reproduce(ctx, opt);
        if (code != 0) throw CLI::RuntimeError(code);
      });
    }};

}  // namespace
}  // namespace implicit::app
