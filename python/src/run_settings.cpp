// The settings of implicit.mcl.run and implicit.slam.run (run_settings.hpp): each keyword is
// converted once, a number against the range of the tool's flag of the same meaning. The text
// settings (method, config, truth, ...) are only checked to be strings here: their values are
// checked by the experiments themselves (experiments/landmark_mcl.cpp, landmark_slam.cpp,
// vehicle.cpp), the one check the tool runs too, with the tool's message.
#include "run_settings.hpp"

#include <stdexcept>
#include <string_view>
#include <vector>

#include <fmt/format.h>

namespace implicit::python {
namespace {

// add_common_options in apps/context.cpp: --threads in_range(0, 1024).
constexpr RunSettingRange kRunThreadsRange{"threads", "--threads", 0, 1024, true};

// The ranges of apps/cmd_mcl.cpp (setup_mcl and add_global_options), keyword by keyword.
constexpr RunSettingRange kMclRanges[] = {
    {"particles", "--particles", 1, kMaxParticles, true},
    {"runs", "--runs", 1, 100'000, true},
    {"p", "--p", 0.0, 10.0, false},
    {"q", "--q", 1e-6, 10.0, false},
    {"gps_std", "--gps-std", 1e-3, 100.0, false},
    {"reference_particles", "--reference-particles", 1, kMaxParticles, true},
    {"control_sd", "--control-sd", 0.0, 100.0, false, 2},
    {"state_sd", "--state-sd", 1e-9, 100.0, false, 3},
    {"range_sd", "--range-sd", 0.0, 100.0, false},
    {"bearing_sd_deg", "--bearing-sd", 0.0, 90.0, false},  // degrees, as the flag
    {"label_gate", "--label-gate", 0.0, 1e6, false},
    {"start_span", "--start-span", 0.0, 1e6, false},
    {"duration", "--duration", 0.0, 1e6, false},
    {"kidnap_at", "--kidnap-at", 0.0, 1e6, false},
    {"kidnap_skip", "--kidnap-skip", 1e-6, 1e6, false},
    {"recovery_alpha_slow", "--recovery-alpha-slow", 1e-9, 1.0, false},
    {"recovery_alpha_fast", "--recovery-alpha-fast", 1e-9, 1.0, false},
    {"kidnap_probability", "--kidnap-probability", 1e-300, 0.5, false},
    {"kld_err", "--kld-err", 1e-6, 1.0, false},
    {"kld_z", "--kld-z", 0.0, 10.0, false},
    {"min_particles", "--min-particles", 1, kMaxParticles, true},
    {"max_particles", "--max-particles", 1, kMaxParticles, true},
    {"cover_spacing", "--cover-spacing", 0.05, 100.0, false},
    {"cover_headings", "--cover-headings", 1, 360, true},
    kRunThreadsRange,
};

// The ranges of apps/cmd_slam.cpp (setup_slam).
constexpr RunSettingRange kSlamRanges[] = {
    {"particles", "--particles", 1, kMaxSlamParticles, true},
    {"datasets", "--datasets", 1, 100'000, true},
    {"laser_every", "--laser-every", 1, 10'000, true},
    {"control_noise", "--control-noise", 1e-6, 10.0, false},
    {"min_range", "--min-range", 0.0, 100.0, false},
    {"range_sd", "--range-sd", 0.0, 100.0, false},
    {"bearing_sd_deg", "--bearing-sd", 0.0, 90.0, false},
    {"gate_chi2", "--gate-chi2", 0.0, 1e6, false},
    {"new_landmark_density", "--new-landmark-density", 0.0, 1e6, false},
    {"control_sd", "--control-sd", 0.0, 100.0, false, 2},
    {"state_sd", "--state-sd", 1e-9, 100.0, false, 3},
    kRunThreadsRange,
};

long long run_int_arg(const py::handle& o, const RunSettingRange& r) {
  return int_arg(o, r.key, static_cast<long long>(r.lo), static_cast<long long>(r.hi));
}

/// The keywords of one runner, each read and checked against the runner's table.
class RunKeywords {
 public:
  RunKeywords(const py::dict& kw, std::span<const RunSettingRange> ranges)
      : kw_(kw), ranges_(ranges) {}

  int integer(const char* key) const { return static_cast<int>(run_int_arg(get(key), range(key))); }
  /// A particle count: beyond the flag's range the message says how much memory it would take.
  int particles(const char* key) const {
    const auto hi = static_cast<long long>(range(key).hi);
    return static_cast<int>(particle_count_arg(get(key), key, hi, kPoseParticleBytes));
  }
  double number(const char* key) const {
    const RunSettingRange& r = range(key);
    return number_arg(get(key), key, r.lo, r.hi);
  }
  /// None: `unset`, the tool's value for a flag not given.
  double number_or(const char* key, double unset) const {
    return get(key).is_none() ? unset : number(key);
  }
  /// None or an empty list: the model's defaults (the flag not given); else exactly `count`
  /// values, each in the flag's range.
  std::vector<double> numbers(const char* key) const {
    const RunSettingRange& r = range(key);
    const py::object o = get(key);
    if (o.is_none()) return {};
    const Array a = require_shape(o, key, {-1}, /*finite=*/false);
    if (a.size() == 0) return {};
    require(a.size() == r.count, "{}: expected {} numbers in [{}, {}], got {}", key, r.count, r.lo,
            r.hi, a.size());
    std::vector<double> v;
    for (py::ssize_t k = 0; k < a.size(); ++k)
      v.push_back(number_arg(py::float_(a.data()[k]), fmt::format("{}[{}]", key, k), r.lo, r.hi));
    return v;
  }
  bool flag(const char* key) const { return bool_arg(get(key), key); }
  /// A str; its value is checked where the tool checks it (the experiment).
  std::string text(const char* key) const {
    const py::object o = get(key);
    require(py::isinstance<py::str>(o), "{}: expected a str, got {}", key, type_name(o));
    return o.cast<std::string>();
  }
  /// None: "" (the tool's flag not given).
  std::string text_or_empty(const char* key) const {
    return get(key).is_none() ? std::string() : text(key);
  }
  /// None: "" (the bundled data).
  std::string path(const char* key) const {
    const py::object o = get(key);
    return o.is_none() ? std::string() : path_arg(o, key).string();
  }

 private:
  py::object get(const char* key) const {
    // Every keyword is passed by the Python wrapper (python/implicit/mcl.py, slam.py).
    if (!kw_.contains(key)) throw std::logic_error(fmt::format("run: missing setting '{}'", key));
    return kw_[key];
  }
  const RunSettingRange& range(const char* key) const {
    for (const RunSettingRange& r : ranges_)
      if (std::string_view(r.key) == key) return r;
    throw std::logic_error(fmt::format("run: no range for the setting '{}'", key));
  }

  const py::dict& kw_;
  std::span<const RunSettingRange> ranges_;
};

}  // namespace

std::span<const RunSettingRange> run_setting_ranges(const std::string& command) {
  if (command == "mcl") return kMclRanges;
  if (command == "slam") return kSlamRanges;
  throw InvalidArgument(fmt::format("command: expected 'mcl' or 'slam', got '{}'", command));
}

experiments::MclSettings mcl_settings(const py::dict& kw) {
  const RunKeywords k(kw, kMclRanges);
  experiments::MclSettings s;
  s.method = k.text("method");
  s.particles = k.particles("particles");
  s.runs = k.integer("runs");
  s.data_dir = k.path("data");
  s.config = experiments::parse_noise_config(k.text("config"));
  s.p = k.number_or("p", -1.0);
  s.q = k.number_or("q", -1.0);
  s.map = experiments::parse_implicit_map(k.text("map"));
  s.clutter = k.flag("clutter");
  s.label_gate = k.number("label_gate");
  s.sigma2 = experiments::parse_sigma2(k.text("sigma2"));
  s.truth = experiments::parse_mcl_truth(k.text("truth"));
  s.gps_std = k.number("gps_std");
  s.reference_particles = k.particles("reference_particles");
  s.model = k.text_or_empty("model");
  s.control_sd = k.numbers("control_sd");
  s.state_sd = k.numbers("state_sd");
  s.range_sd = k.number("range_sd");
  s.bearing_sd_deg = k.number("bearing_sd_deg");
  s.init = k.text("init");
  s.start_span = k.number("start_span");
  s.duration = k.number("duration");
  s.kidnap_at = k.number_or("kidnap_at", -1.0);
  s.kidnap_skip = k.number("kidnap_skip");
  s.recovery = k.text("recovery");
  s.recovery_alpha_slow = k.number("recovery_alpha_slow");
  s.recovery_alpha_fast = k.number("recovery_alpha_fast");
  s.kidnap_probability = k.number("kidnap_probability");
  s.kld = k.flag("kld");
  s.kld_err = k.number("kld_err");
  s.kld_z = k.number("kld_z");
  s.min_particles = k.particles("min_particles");
  s.max_particles = k.particles("max_particles");
  s.cover_spacing = k.number("cover_spacing");
  s.cover_headings = k.integer("cover_headings");
  return s;
}

experiments::SlamSettings slam_settings(const py::dict& kw) {
  const RunKeywords k(kw, kSlamRanges);
  experiments::SlamSettings s;
  s.method = k.text("method");
  s.particles = k.particles("particles");
  s.datasets = k.integer("datasets");
  s.data_dir = k.path("data");
  s.association = k.text("association");
  s.truth = experiments::parse_slam_truth(k.text("truth"));
  s.laser_every = k.integer("laser_every");
  s.control_noise = k.number("control_noise");
  s.min_range = k.number("min_range");
  s.range_sd = k.number("range_sd");
  s.bearing_sd_deg = k.number("bearing_sd_deg");
  s.gate_chi2 = k.number("gate_chi2");
  s.new_landmark_density = k.number("new_landmark_density");
  s.model = k.text_or_empty("model");
  s.control_sd = k.numbers("control_sd");
  s.state_sd = k.numbers("state_sd");
  return s;
}

experiments::RunContext run_context(const py::handle& seed, const py::handle& out,
                                    const py::handle& threads, const py::handle& verbose) {
  experiments::RunContext ctx;
  ctx.seed = seed_arg(seed, "seed");
  ctx.out_dir = out.is_none() ? std::string() : path_arg(out, "out").string();
  ctx.threads = static_cast<int>(run_int_arg(threads, kRunThreadsRange));
  ctx.quiet = !bool_arg(verbose, "verbose");
  ctx.json = ctx.quiet;
  return ctx;
}

}  // namespace implicit::python
