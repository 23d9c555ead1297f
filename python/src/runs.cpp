// The experiments of the command-line tool, called with the same settings structs and the same
// code (apps/exp_*.cpp), so implicit.mcl.run(...) returns the numbers of `implicit mcl --json`.
// The result crosses as JSON text; the Python side parses it into a dict.

#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include "common.hpp"
#include "experiments.hpp"
#include "implicit/core/parallel.hpp"

namespace implicit::python {
namespace {

app::RunContext context(std::uint64_t seed, const std::string& out, int threads) {
  app::RunContext ctx;
  ctx.seed = seed;
  ctx.out_dir = out;
  ctx.threads = threads;
  ctx.quiet = true;
  ctx.json = true;
  return ctx;
}

template <typename Settings, typename Run>
std::string run_json(const Settings& s, std::uint64_t seed, const std::string& out, int threads,
                     Run run) {
  const app::RunContext ctx = context(seed, out, threads);
  nlohmann::json j;
  {
    py::gil_scoped_release unlocked;
    ThreadLimit limit(threads);
    j = run(s, ctx);
  }
  return j.dump();
}

}  // namespace

void init_runs(py::module_& m) {
  m.def(
      "_run_mcl",
      [](const py::dict& kw, std::uint64_t seed, const std::string& out, int threads) {
        app::MclSettings s;
        s.method = kw["method"].cast<std::string>();
        s.particles = kw["particles"].cast<int>();
        s.runs = kw["runs"].cast<int>();
        s.data_dir = kw["data"].cast<std::string>();
        s.config = kw["config"].cast<std::string>();
        s.p = kw["p"].cast<double>();
        s.q = kw["q"].cast<double>();
        s.map = kw["map"].cast<std::string>();
        s.clutter = kw["clutter"].cast<bool>();
        s.sigma2 = kw["sigma2"].cast<std::string>();
        s.truth = kw["truth"].cast<std::string>();
        s.gps_std = kw["gps_std"].cast<double>();
        s.reference_particles = kw["reference_particles"].cast<int>();
        s.model = kw["model"].cast<std::string>();
        s.control_sd = kw["control_sd"].cast<std::vector<double>>();
        s.state_sd = kw["state_sd"].cast<std::vector<double>>();
        s.range_sd = kw["range_sd"].cast<double>();
        s.bearing_sd_deg = kw["bearing_sd_deg"].cast<double>();
        s.init = kw["init"].cast<std::string>();
        s.start_span = kw["start_span"].cast<double>();
        s.duration = kw["duration"].cast<double>();
        s.kidnap_at = kw["kidnap_at"].cast<double>();
        s.kidnap_skip = kw["kidnap_skip"].cast<double>();
        s.recovery = kw["recovery"].cast<std::string>();
        s.recovery_alpha_slow = kw["recovery_alpha_slow"].cast<double>();
        s.recovery_alpha_fast = kw["recovery_alpha_fast"].cast<double>();
        s.kidnap_probability = kw["kidnap_probability"].cast<double>();
        s.kld = kw["kld"].cast<bool>();
        s.kld_err = kw["kld_err"].cast<double>();
        s.kld_z = kw["kld_z"].cast<double>();
        s.min_particles = kw["min_particles"].cast<int>();
        s.max_particles = kw["max_particles"].cast<int>();
        s.cover_spacing = kw["cover_spacing"].cast<double>();
        s.cover_headings = kw["cover_headings"].cast<int>();
        return run_json(s, seed, out, threads, &app::run_mcl);
      },
      py::arg("settings"), py::arg("seed"), py::arg("out"), py::arg("threads"));
  m.def(
      "_run_slam",
      [](const py::dict& kw, std::uint64_t seed, const std::string& out, int threads) {
        app::SlamSettings s;
        s.method = kw["method"].cast<std::string>();
        s.particles = kw["particles"].cast<int>();
        s.datasets = kw["datasets"].cast<int>();
        s.data_dir = kw["data"].cast<std::string>();
        s.association = kw["association"].cast<std::string>();
        s.truth = kw["truth"].cast<std::string>();
        s.laser_every = kw["laser_every"].cast<int>();
        s.control_noise = kw["control_noise"].cast<double>();
        s.min_range = kw["min_range"].cast<double>();
        s.range_sd = kw["range_sd"].cast<double>();
        s.bearing_sd_deg = kw["bearing_sd_deg"].cast<double>();
        s.gate_chi2 = kw["gate_chi2"].cast<double>();
        s.new_landmark_density = kw["new_landmark_density"].cast<double>();
        s.model = kw["model"].cast<std::string>();
        s.control_sd = kw["control_sd"].cast<std::vector<double>>();
        s.state_sd = kw["state_sd"].cast<std::vector<double>>();
        return run_json(s, seed, out, threads, &app::run_slam);
      },
      py::arg("settings"), py::arg("seed"), py::arg("out"), py::arg("threads"));
  m.def(
      "_run_slit",
      [](int samples, int runs, const std::string& mode, const std::string& estimator,
         std::uint64_t seed, const std::string& out, int threads) {
        app::SlitSettings s;
        s.samples = samples;
        s.runs = runs;
        s.mode = mode;
        s.estimator = estimator;
        return run_json(s, seed, out, threads, &app::run_slit);
      },
      py::arg("samples"), py::arg("runs"), py::arg("mode"), py::arg("estimator"), py::arg("seed"),
      py::arg("out"), py::arg("threads"));
  m.def(
      "_run_himmelblau",
      [](int runs, int samples, std::uint64_t seed, const std::string& out, int threads) {
        app::HimmelblauSettings s;
        s.runs = runs;
        s.samples = samples;
        return run_json(s, seed, out, threads, &app::run_himmelblau);
      },
      py::arg("runs"), py::arg("samples"), py::arg("seed"), py::arg("out"), py::arg("threads"));
  m.def(
      "_run_arm",
      [](const std::string& estimator, std::uint64_t seed, const std::string& out, int threads) {
        app::ArmSettings s;
        s.estimator = estimator;
        return run_json(s, seed, out, threads, &app::run_arm);
      },
      py::arg("estimator"), py::arg("seed"), py::arg("out"), py::arg("threads"));
}

}  // namespace implicit::python
