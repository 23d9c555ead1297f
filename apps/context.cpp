#include "context.hpp"

#include <unistd.h>

#include <cstdio>

#include <fmt/format.h>

namespace implicit::app {

Progress::Progress(std::string label, std::size_t total, bool enabled, Style style)
    : label_(std::move(label)),
      total_(total),
      enabled_(enabled && total > 0),
      tty_(style == Style::kAuto && isatty(fileno(stderr)) != 0),
      every_tick_(style == Style::kLines),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

void Progress::tick(std::size_t n) {
  const std::size_t done = done_.fetch_add(n) + n;
  if (enabled_) draw(done, false);
}

void Progress::tick(std::size_t n, const std::string& note) {
  const std::size_t done = done_.fetch_add(n) + n;
  if (enabled_) draw(done, false, note);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  draw(done_.load(), true);
  std::lock_guard lock(mutex_);
  finished_ = true;
}

void Progress::draw(std::size_t done, bool final, const std::string& note) {
  std::lock_guard lock(mutex_);
  if (finished_) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double fraction = total_ ? std::min(1.0, static_cast<double>(done) / total_) : 1.0;
  const int percent = static_cast<int>(fraction * 100.0);
  if (tty_) {
    if (!final && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    const int width = 30;
    const int filled = static_cast<int>(fraction * width);
    const double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    fmt::print(stderr, "\r{:<24} [{:<{}}] {:3d}% {}/{} elapsed {:.0f}s ETA {:.0f}s   ",
               label_.substr(0, 24), std::string(filled, '#'), width, percent, done, total_,
               elapsed, eta);
    if (final) fmt::print(stderr, "\n");
  } else {
    // Plain lines: every 10 % and at the end (every tick in Style::kLines).
    if (!final && !every_tick_ && (percent / 10 == last_percent_ / 10)) return;
    if (final && last_percent_ == percent) return;  // the last tick said it all
    last_percent_ = percent;
    const double eta = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    if (every_tick_)
      fmt::print(stderr, "{}: {}% done, {:.1f}s elapsed, ETA {:.0f}s{}{}\n", label_, percent,
                 elapsed, eta, note.empty() ? "" : "; next: ", note);
    else
      fmt::print(stderr, "{}: {}/{} ({}%), {:.1f}s\n", label_, done, total_, percent, elapsed);
  }
  std::fflush(stderr);
}

std::filesystem::path RunContext::csv_path(const std::string& name) const {
  if (out_dir.empty()) return {};
  std::filesystem::create_directories(out_dir);
  return out_dir / name;
}

}  // namespace implicit::app

#include <CLI/CLI.hpp>

namespace implicit::app {
void add_common_options(CLI::App& sub, RunContext& ctx) {
  sub.add_option("--seed", ctx.seed, "Random seed (runs with the same seed are bit-identical)")
      ->capture_default_str();
  sub.add_flag("--json", ctx.json, "Print one JSON object on stdout and nothing else");
  auto* out = sub.add_option("--out", ctx.out_dir, "Folder for CSV output (figures, trajectories)");
  if (!ctx.out_dir.empty()) out->capture_default_str();
  sub.add_option("--threads", ctx.threads, "Worker threads (0 = all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  sub.add_flag("--quiet", ctx.quiet, "No progress output on stderr");
  sub.add_flag("--resume", ctx.resume,
               "Skip the runs finished by an earlier, interrupted or failed command with the same "
               "--out and settings (kept in OUT/.resume)");
}

void set_examples(CLI::App& sub, const std::vector<std::string>& commands) {
  std::string text = "\nExamples:\n";
  for (const auto& c : commands) text += "  " + c + "\n";
  sub.footer(text);
}
}  // namespace implicit::app
