#include "context.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "implicit/core/error.hpp"
#include "implicit/core/version.hpp"

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
  done_.fetch_add(n);
  if (enabled_) draw(false);
}

void Progress::tick(std::size_t n, const std::string& note) {
  done_.fetch_add(n);
  if (enabled_) draw(false, note);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  draw(true);
  std::lock_guard lock(mutex_);
  finished_ = true;
}

void Progress::draw(bool final, const std::string& note) {
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

namespace {
// Temporary files being written, for the signal handler: fixed storage, since a handler may only
// read memory and call async-signal-safe functions (unlink, write, _exit).
constexpr int kSlots = 64;
constexpr std::size_t kPathBytes = 4096;
char pending_paths[kSlots][kPathBytes];
std::atomic<bool> pending_used[kSlots];
std::atomic<int> outputs_completed{0};

int register_pending(const std::filesystem::path& p) {
  const std::string s = p.string();
  if (s.size() >= kPathBytes) return -1;
  for (int i = 0; i < kSlots; ++i) {
    bool expected = false;
    if (!pending_used[i].load() && pending_used[i].compare_exchange_strong(expected, true)) {
      std::copy(s.c_str(), s.c_str() + s.size() + 1, pending_paths[i]);
      return i;
    }
  }
  return -1;  // more than kSlots at once: that file's temporary name may remain after a signal
}

void release_pending(int slot) {
  if (slot >= 0) pending_used[slot].store(false);
}

void write_stderr(const char* text) {
  std::size_t n = 0;
  while (text[n] != '\0') ++n;
  [[maybe_unused]] const auto ignored = ::write(STDERR_FILENO, text, n);
}

extern "C" void on_stop_signal(int signal) {
  int removed = 0;
  for (int i = 0; i < kSlots; ++i)
    if (pending_used[i].load() && ::unlink(pending_paths[i]) == 0) ++removed;
  // Digits by hand: snprintf is not async-signal-safe.
  char number[16];
  auto digits = [&number](int v) {
    char tmp[16];
    int k = 0;
    do {
      tmp[k++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v > 0 && k < 15);
    for (int i = 0; i < k; ++i) number[i] = tmp[k - 1 - i];
    number[k] = '\0';
    return number;
  };
  write_stderr(signal == SIGINT ? "\nimplicit: stopped by SIGINT; "
                                : "\nimplicit: stopped by SIGTERM; ");
  write_stderr(digits(outputs_completed.load()));
  write_stderr(" output file(s) were complete and are kept, ");
  write_stderr(digits(removed));
  write_stderr(" unfinished one(s) removed\n");
  ::_exit(128 + signal);
}
}  // namespace

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

OutputFile::OutputFile(std::filesystem::path path, Mode mode, std::string flag)
    : path_(std::move(path)), flag_(std::move(flag)) {
  // Same folder, so that the rename is atomic; the pid keeps concurrent runs apart.
  temporary_ = path_;
  temporary_ += fmt::format(".tmp{}", ::getpid());
  std::error_code ec;
  fresh_ = !std::filesystem::exists(path_, ec);
  if (mode == Mode::kAppend && !fresh_)
    std::filesystem::copy_file(path_, temporary_, std::filesystem::copy_options::overwrite_existing,
                               ec);
  slot_ = register_pending(temporary_);
  out_ = std::make_unique<std::ofstream>(
      temporary_, mode == Mode::kAppend && !fresh_ ? std::ios::app : std::ios::trunc);
}

OutputFile::~OutputFile() {
  if (committed_) return;
  out_.reset();
  std::error_code ec;
  std::filesystem::remove(temporary_, ec);
  release_pending(slot_);
}

std::ostream& OutputFile::stream() { return *out_; }

void OutputFile::commit() {
  out_->flush();
  const bool written = static_cast<bool>(*out_);
  out_->close();
  std::error_code ec;
  if (written && !out_->fail()) std::filesystem::rename(temporary_, path_, ec);
  if (!written || out_->fail() || ec) {
    std::filesystem::remove(temporary_, ec);
    release_pending(slot_);
    slot_ = -1;
    throw InvalidArgument(
        fmt::format("{}: {}: expected a writable output file, got a failed write{}", flag_,
                    path_.string(), ec ? " (" + ec.message() + ")" : ""));
  }
  committed_ = true;
  release_pending(slot_);
  ++outputs_completed;
}

void print_json(nlohmann::json result) {
  result["version"] = implicit::version();
  result["commit"] = implicit::git_commit();
  fmt::print("{}\n", result.dump(2));
}

void require_scored(const nlohmann::json& result, const std::string& command,
                    const std::vector<std::string>& finite,
                    const std::vector<std::string>& positive, bool allow_empty) {
  std::vector<std::string> missing;
  for (const auto& key : finite) {
    const auto it = result.find(key);
    if (it == result.end() || !it->is_number() || !std::isfinite(it->get<double>()))
      missing.push_back(key + " is not a finite number");
  }
  for (const auto& key : positive) {
    const auto it = result.find(key);
    if (it == result.end() || !it->is_number() || !(it->get<double>() > 0.0))
      missing.push_back(key + " is 0");
  }
  if (missing.empty()) return;
  std::string list;
  for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
  fmt::print(
      stderr, "implicit {}: warning: the run scored nothing: {}{}\n", command, list,
      allow_empty ? " (allowed by --allow-empty)" : "; exit code 1 (--allow-empty allows it)");
  if (!allow_empty) throw CLI::RuntimeError(1);
}

CLI::Validator in_range(int lo, int hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        const char* begin = text.c_str();
        char* end = nullptr;
        errno = 0;
        const long long v = std::strtoll(begin, &end, 10);
        if (text.empty() || end != begin + text.size() || errno == ERANGE)
          return fmt::format("expected an integer in [{}, {}], got '{}'", lo, hi, printable(text));
        if (v < lo || v > hi) return fmt::format("expected [{}, {}], got {}", lo, hi, v);
        return {};
      },
      fmt::format("INT in [{} - {}]", lo, hi));
}

CLI::Validator in_range(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        const char* begin = text.c_str();
        char* end = nullptr;
        const double v = std::strtod(begin, &end);
        if (text.empty() || end != begin + text.size() || !std::isfinite(v))
          return fmt::format("expected a finite number in [{}, {}], got '{}'", lo, hi,
                             printable(text));
        if (v < lo || v > hi) return fmt::format("expected [{}, {}], got {}", lo, hi, v);
        return {};
      },
      fmt::format("FLOAT in [{} - {}]", lo, hi));
}

void add_common_options(CLI::App& sub, RunContext& ctx) {
  // Unsigned: "-1" would otherwise wrap to 2^64 - 1 without a word.
  sub.add_option("--seed", ctx.seed, "Random seed (runs with the same seed are bit-identical)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            const bool digits =
                !text.empty() && text.size() <= 20 &&
                std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
            errno = 0;
            if (!digits || (std::strtoull(text.c_str(), nullptr, 10), errno == ERANGE))
              return fmt::format("expected an integer in [0, 2^64 - 1], got '{}'", printable(text));
            return {};
          },
          "UINT64"))
      ->capture_default_str();
  sub.add_flag("--json", ctx.json, "Print one JSON object on stdout and nothing else");
  auto* out = sub.add_option("--out", ctx.out_dir, "Folder for CSV output (figures, trajectories)");
  if (!ctx.out_dir.empty()) out->capture_default_str();
  sub.add_option("--threads", ctx.threads, "Worker threads (0 = all cores)")
      ->check(in_range(0, 1024))
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
