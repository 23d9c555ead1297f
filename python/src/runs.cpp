// The experiments of the command-line tool, called with the same settings structs and the same
// code (experiments/), so implicit.mcl.run(...) returns the numbers of `implicit mcl --json`.
// The settings are checked as the tool checks its flags (run_settings.cpp). The result crosses as
// JSON text; the Python side parses it into a dict.

#include <pybind11/stl.h>

#include <exception>
#include <memory>

#include <nlohmann/json.hpp>

#include "common.hpp"
#include "experiments/control.hpp"
#include "experiments/landmark_mcl.hpp"
#include "experiments/landmark_slam.hpp"
#include "implicit/core/parallel.hpp"
#include "run_settings.hpp"

namespace implicit::python {
namespace {

template <typename Settings, typename Run>
std::string run_json(const Settings& s, const experiments::RunContext& ctx, Run run) {
  nlohmann::json j;
  {
    py::gil_scoped_release unlocked;
    ThreadLimit limit(ctx.threads);
    j = run(s, ctx);
  }
  return j.dump();
}

/// run_json with progress (run_settings.hpp).
template <typename Settings, typename Run>
std::string run_json(const Settings& s, experiments::RunContext ctx, const py::object& progress,
                     Run run) {
  return with_python_progress(ctx, progress, [&] { return run_json(s, ctx, run); });
}

}  // namespace

void init_runs(py::module_& m) {
  // The settings are checked (run_settings.cpp) before anything runs; seed, out and threads as
  // the tool's --seed, --out and --threads.
  m.def(
      "_run_mcl",
      [](const py::dict& kw, const py::object& seed, const py::object& out,
         const py::object& threads, const py::object& verbose, const py::object& progress) {
        const experiments::MclSettings s = mcl_settings(kw);
        return run_json(s, run_context(seed, out, threads, verbose), progress,
                        &experiments::run_mcl);
      },
      py::arg("settings"), py::arg("seed"), py::arg("out"), py::arg("threads"),
      py::arg("verbose") = false, py::arg("progress") = py::none());
  m.def(
      "_run_slam",
      [](const py::dict& kw, const py::object& seed, const py::object& out,
         const py::object& threads, const py::object& verbose, const py::object& progress) {
        const experiments::SlamSettings s = slam_settings(kw);
        return run_json(s, run_context(seed, out, threads, verbose), progress,
                        &experiments::run_slam);
      },
      py::arg("settings"), py::arg("seed"), py::arg("out"), py::arg("threads"),
      py::arg("verbose") = false, py::arg("progress") = py::none());
  m.def(
      "_run_setting_ranges",
      [](const std::string& command) {
        py::list out;
        for (const RunSettingRange& r : run_setting_ranges(command))
          out.append(py::dict(py::arg("key") = r.key, py::arg("flag") = r.flag,
                              py::arg("lo") = r.lo, py::arg("hi") = r.hi,
                              py::arg("integer") = r.integer, py::arg("count") = r.count));
        return out;
      },
      py::arg("command"),
      "The numeric ranges of implicit.mcl.run ('mcl') or slam.run ('slam'): key, the tool's "
      "flag, lo, hi, integer, count (values of a list flag; 0: one value).");
  m.def(
      "_run_slit",
      [](int samples, int runs, const std::string& mode, const std::string& estimator,
         const py::object& seed, const py::object& out, const py::object& threads) {
        experiments::SlitSettings s;
        s.samples = samples;
        s.runs = runs;
        s.mode = experiments::parse_slit_mode(mode);
        s.estimator = experiments::parse_slit_estimator(estimator);
        return run_json(s, run_context(seed, out, threads), &experiments::run_slit);
      },
      py::arg("samples"), py::arg("runs"), py::arg("mode"), py::arg("estimator"), py::arg("seed"),
      py::arg("out"), py::arg("threads"));
  m.def(
      "_run_himmelblau",
      [](int runs, int samples, const py::object& seed, const py::object& out,
         const py::object& threads) {
        experiments::HimmelblauSettings s;
        s.runs = runs;
        s.samples = samples;
        return run_json(s, run_context(seed, out, threads), &experiments::run_himmelblau);
      },
      py::arg("runs"), py::arg("samples"), py::arg("seed"), py::arg("out"), py::arg("threads"));
  m.def(
      "_run_arm",
      [](const std::string& estimator, const py::object& seed, const py::object& out,
         const py::object& threads) {
        experiments::ArmSettings s;
        s.estimator = experiments::parse_arm_estimator(estimator);
        return run_json(s, run_context(seed, out, threads), &experiments::run_arm);
      },
      py::arg("estimator"), py::arg("seed"), py::arg("out"), py::arg("threads"));
}

}  // namespace implicit::python
