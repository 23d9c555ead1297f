// ProgressBar and RunContext (run_context.hpp).
#include "experiments/run_context.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit::experiments {

ProgressBar::ProgressBar(std::string label, std::size_t total, bool enabled, Style style)
    : label_(std::move(label)),
      total_(total),
      enabled_(enabled && total > 0),
      tty_(style == Style::kAuto && isatty(fileno(stderr)) != 0),
      every_tick_(style == Style::kLines),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

ProgressBar::ProgressBar(std::string label, std::size_t total, bool enabled, ProgressHook hook)
    : ProgressBar(std::move(label), total, enabled) {
  hook_ = std::move(hook);
  last_report_ = start_;
}

ProgressBar::~ProgressBar() {
  if (!enabled_ || finished_) return;
  draw(true);
  std::lock_guard lock(mutex_);
  finished_ = true;
}

void ProgressBar::tick(std::size_t n) {
  done_.fetch_add(n);
  if (hook_) report(false);
  if (enabled_) draw(false);
}

void ProgressBar::tick(std::size_t n, const std::string& note) {
  done_.fetch_add(n);
  if (hook_) report(false);
  if (enabled_) draw(false, note);
}

void ProgressBar::finish() {
  // The work is complete even when runs reused from --resume never ticked: the hook's last
  // call says total.
  if (hook_) {
    done_.store(std::max(done_.load(), total_));
    report(true);
  }
  if (!enabled_ || finished_) return;
  draw(true);
  std::lock_guard lock(mutex_);
  finished_ = true;
}

void ProgressBar::check() const {
  if (stopped_.load()) throw RunStopped();
}

void ProgressBar::report(bool final) {
  check();
  std::lock_guard lock(hook_mutex_);
  check();  // another worker's call may have thrown while this one waited
  // The count is read under the lock: calls never go backwards (as draw()).
  const std::size_t done = std::min(done_.load(), total_);
  if (reported_any_ && done == reported_) return;
  const auto now = std::chrono::steady_clock::now();
  if (!final && done < total_ && now - last_report_ < std::chrono::milliseconds(100)) return;
  last_report_ = now;
  reported_ = done;
  reported_any_ = true;
  try {
    hook_(done, total_);
  } catch (...) {
    stopped_.store(true);
    throw;
  }
}

void ProgressBar::draw(bool final, const std::string& note) {
  std::lock_guard lock(mutex_);
  if (finished_) return;
  // The count is read under the lock, not passed from tick(): workers that finish together
  // would otherwise print in the order they got the lock, a later line with a smaller count.
  const std::size_t done = done_.load();
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

void create_out_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  if (std::filesystem::is_directory(dir, ec)) return;
  if (std::filesystem::exists(dir, ec))
    throw InvalidArgument(
        fmt::format("--out {}: expected a folder for the output files, got a "
                    "file that is not a folder",
                    dir.string()));
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw InvalidArgument(
        fmt::format("--out {}: expected a folder that can be created for the "
                    "output files, got an error ({})",
                    dir.string(), ec.message()));
}

std::filesystem::path RunContext::csv_path(const std::string& name) const {
  if (out_dir.empty()) return {};
  create_out_dir(out_dir);
  return out_dir / name;
}

}  // namespace implicit::experiments
