// `implicit mcl --params` (nav2_params.hpp): nav2's AMCL keys as the laser run's flags.
#include "nav2_params.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <exception>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "implicit/core/error.hpp"
#include "implicit/robot/nav2_params.hpp"

namespace implicit::app {
namespace {

// The keys whose meaning is one flag's (nav2's names and units; docs/cli.md has the table).
struct Nav2FlagKey {
  std::string_view key, flag;
};
constexpr std::array kNav2FlagKeys = {
    Nav2FlagKey{"z_hit", "--z-hit"},
    Nav2FlagKey{"z_rand", "--z-rand"},
    Nav2FlagKey{"sigma_hit", "--sigma-hit"},
    Nav2FlagKey{"max_beams", "--max-beams"},
    Nav2FlagKey{"laser_likelihood_max_dist", "--laser-max-dist"},
    Nav2FlagKey{"laser_max_range", "--laser-max-range"},
    Nav2FlagKey{"z_short", "--z-short"},
    Nav2FlagKey{"z_max", "--z-max"},
    Nav2FlagKey{"lambda_short", "--lambda-short"},
    Nav2FlagKey{"update_min_d", "--update-min-d"},
    Nav2FlagKey{"update_min_a", "--update-min-a"},
    Nav2FlagKey{"pf_err", "--kld-err"},
    Nav2FlagKey{"pf_z", "--kld-z"},
    Nav2FlagKey{"min_particles", "--min-particles"},
    Nav2FlagKey{"max_particles", "--max-particles"},
};

// Keys of AMCL that steer the ROS node, not the filter: nothing to do on recorded data.
constexpr std::array<std::string_view, 14> kNav2PlumbingKeys = {"use_sim_time",
                                                                "global_frame_id",
                                                                "odom_frame_id",
                                                                "tf_broadcast",
                                                                "transform_tolerance",
                                                                "save_pose_rate",
                                                                "map_topic",
                                                                "first_map_only",
                                                                "always_reset_initial_pose",
                                                                "set_initial_pose",
                                                                "scan_topic",
                                                                "base_frame_id",
                                                                "bond_disable_heartbeat_timeout",
                                                                "service_introspection_mode"};

class Nav2Applier {
 public:
  Nav2Applier(CLI::App& sub, const robot::Nav2Parameters& p, Nav2ParamsRecord& record)
      : sub_(sub), p_(p), record_(record) {}

  // Sets `flag` to `values` unless the command line gave it; `keys` are the file's keys behind it.
  void set(std::string_view flag, const std::vector<std::string>& values,
           const std::vector<const robot::Nav2Parameter*>& keys) {
    CLI::Option* o = sub_.get_option(std::string(flag));
    if (o->count() > 0 && !set_here_.contains(o)) {
      for (const auto* k : keys) record_.overridden.push_back(k->key);
      return;
    }
    try {
      o->clear();
      for (const auto& v : values) o->add_result(v);
      o->run_callback();
    } catch (const CLI::Error& e) {
      fail(*keys.front(), e.what());
    }
    set_here_.insert(o);
    std::string text = std::string(flag);
    for (const auto& v : values) text += " " + v;
    for (const auto* k : keys) {
      auto same = std::find_if(record_.used.begin(), record_.used.end(),
                               [&](const auto& u) { return u.first == k->key; });
      if (same == record_.used.end())
        record_.used.emplace_back(k->key, text);
      else
        same->second += ", " + text;
    }
  }

  [[noreturn]] void fail(const robot::Nav2Parameter& k, const std::string& what) const {
    throw InvalidArgument(
        fmt::format("mcl --params {}:{}: {}: {}", p_.source, k.line, k.key, printable(what, 200)));
  }

  void not_used(const robot::Nav2Parameter& k, std::string_view why) {
    record_.not_used.push_back(k.key);
    fmt::print(stderr, "implicit mcl: --params {}:{}: {} is not used: {}\n", p_.source, k.line,
               k.key, why);
  }

 private:
  CLI::App& sub_;
  const robot::Nav2Parameters& p_;
  Nav2ParamsRecord& record_;
  std::set<const CLI::Option*> set_here_;
};

double nav2_number(const Nav2Applier& a, const robot::Nav2Parameter& k) {
  try {
    std::size_t used = 0;
    const double v = std::stod(k.value, &used);
    if (used == k.value.size()) return v;
  } catch (const std::exception&) {
  }
  a.fail(k, fmt::format("expected a number, got '{}'", k.value));
}

}  // namespace

Nav2ParamsRecord apply_nav2_params(CLI::App& sub, const std::string& file, bool bag_data) {
  const robot::Nav2Parameters p = robot::read_nav2_parameters(file, "amcl");
  Nav2ParamsRecord record;
  record.file = file;
  Nav2Applier a(sub, p, record);
  std::set<std::string> handled;
  // The odometry model: AMCL's differential drive is the one here (alpha1..alpha4).
  if (const auto* k = p.find("robot_model_type")) {
    handled.insert(k->key);
    if (k->value.find("Omni") != std::string::npos || k->value == "omnidirectional")
      a.fail(*k, fmt::format("expected the differential drive (nav2_amcl::DifferentialMotionModel; "
                             "the odometry model here), got '{}'",
                             k->value));
    if (k->value.find("Differential") == std::string::npos && k->value != "differential")
      a.fail(*k, fmt::format("expected nav2_amcl::DifferentialMotionModel, got '{}'", k->value));
    record.used.emplace_back(k->key, "the odometry motion model");
  }
  std::vector<const robot::Nav2Parameter*> alphas;
  std::vector<std::string> alpha_values;
  for (const char* key : {"alpha1", "alpha2", "alpha3", "alpha4"}) {
    const auto* k = p.find(key);
    handled.insert(key);
    if (k) alphas.push_back(k);
    alpha_values.push_back(k ? k->value : "0.2");  // AMCL's default
  }
  if (!alphas.empty()) a.set("--filter-alphas", alpha_values, alphas);
  if (const auto* k = p.find("alpha5")) {
    handled.insert(k->key);
    a.not_used(*k, "only the omnidirectional model has a fifth alpha");
  }
  if (const auto* k = p.find("laser_model_type")) {
    handled.insert(k->key);
    if (k->value == "likelihood_field" || k->value == "likelihood_field_prob")
      a.set("--laser-model", {"likelihood-field"}, {k});
    else if (k->value == "beam")
      a.set("--laser-model", {"beam"}, {k});
    else
      a.fail(*k, fmt::format("expected likelihood_field, likelihood_field_prob or beam, got '{}'",
                             k->value));
  }
  for (const auto& [key, flag] : kNav2FlagKeys)
    if (const auto* k = p.find(key)) {
      handled.insert(k->key);
      a.set(flag, {k->value}, {k});
    }
  // AMCL always adapts its particle count, starting from max_particles.
  if (p.find("min_particles") || p.find("max_particles")) {
    std::vector<const robot::Nav2Parameter*> keys;
    for (const char* key : {"min_particles", "max_particles"})
      if (const auto* k = p.find(key)) keys.push_back(k);
    a.set("--kld", {"true"}, keys);
    if (const auto* k = p.find("max_particles")) a.set("--particles", {k->value}, {k});
  }
  // Injection only when both averages move (AMCL's w_slow, w_fast start at 0).
  // A rate of 0 (nav2's default) turns recovery off.
  const auto* slow = p.find("recovery_alpha_slow");
  const auto* fast = p.find("recovery_alpha_fast");
  for (const auto* k : {slow, fast})
    if (k) handled.insert(k->key);
  if (slow && fast && nav2_number(a, *slow) > 0 && nav2_number(a, *fast) > 0) {
    a.set("--recovery-alpha-slow", {slow->value}, {slow});
    a.set("--recovery-alpha-fast", {fast->value}, {fast});
    a.set("--recovery", {"uniform"}, {slow, fast});
  } else if (slow || fast) {
    std::vector<const robot::Nav2Parameter*> keys;
    for (const auto* k : {slow, fast})
      if (k) keys.push_back(k);
    a.set("--recovery", {"none"}, keys);
  }
  if (const auto* k = p.find("laser_min_range")) {
    handled.insert(k->key);
    if (nav2_number(a, *k) > 0)
      a.not_used(*k, "readings below a minimum range are not dropped here");
    else
      record.used.emplace_back(k->key, "no minimum range (as here)");
  }
  if (bag_data) {
    for (const auto& [key, flag] :
         {std::pair{"scan_topic", "--scan-topic"}, std::pair{"base_frame_id", "--base-frame"}})
      if (const auto* k = p.find(key)) {
        handled.insert(k->key);
        // AMCL names its topic relative to its namespace; a bag records it absolute.
        a.set(flag, {k->value.starts_with('/') ? k->value : "/" + k->value}, {k});
      }
  }
  for (const auto& k : p.entries) {
    if (handled.contains(k.key)) continue;
    const std::string_view head = std::string_view(k.key).substr(0, k.key.find('.'));
    if (k.key == "resample_interval")
      a.not_used(k, "this filter resamples when the effective sample size falls below M/2");
    else if (k.key == "scan_topic" || k.key == "base_frame_id")
      a.not_used(k, "used only with a ROS bag as --data");
    else if (k.key == "do_beamskip" || k.key.starts_with("beam_skip_"))
      a.not_used(k, "beam skipping is not implemented; every chosen beam counts");
    else if (std::find(kNav2PlumbingKeys.begin(), kNav2PlumbingKeys.end(), head) !=
                 kNav2PlumbingKeys.end() ||
             head == "initial_pose")
      a.not_used(k, head == "initial_pose" || head == "set_initial_pose"
                        ? "the start is the log's (--init known) or none (--init global)"
                        : "it steers the ROS node, not the filter");
    else
      a.not_used(k, "not one of AMCL's filter parameters this program knows");
  }
  return record;
}

}  // namespace implicit::app
