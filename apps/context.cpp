#include "context.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "implicit/core/error.hpp"
#include "implicit/core/version.hpp"

namespace implicit::app {

namespace {
// The plot script (or other child) being waited for: the signal handler stops its process group.
std::atomic<pid_t> running_child{0};

void write_stderr(const char* text) {
  std::size_t n = 0;
  while (text[n] != '\0') ++n;
  [[maybe_unused]] const auto ignored = ::write(STDERR_FILENO, text, n);
}

// Only async-signal-safe calls: kill, waitpid, nanosleep. SIGTERM first (python exits at once);
// SIGKILL after two seconds for a child that ignores it.
void stop_running_child() {
  const pid_t child = running_child.load();
  if (child <= 0) return;
  ::kill(-child, SIGTERM);
  for (int i = 0; i < 200; ++i) {
    const pid_t r = ::waitpid(child, nullptr, WNOHANG);
    if (r == child || (r < 0 && errno != EINTR)) return;  // ended (or reaped by the main thread)
    const timespec pause{0, 10'000'000};
    ::nanosleep(&pause, nullptr);
  }
  ::kill(-child, SIGKILL);
  ::waitpid(child, nullptr, 0);
}

extern "C" void on_stop_signal(int signal) {
  // The child first: it could otherwise recreate a file just removed.
  stop_running_child();
  const int removed = remove_unfinished_outputs();
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
  write_stderr(digits(completed_outputs()));
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

int run_child_process(const std::vector<std::string>& args, const std::filesystem::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  // The log too is written under a temporary name and renamed when the child ended; a signal
  // removes it with the other unfinished outputs.
  std::filesystem::path partial_log = log;
  partial_log += fmt::format(".tmp{}", ::getpid());
  const UnfinishedOutput unfinished_log(partial_log);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, partial_log.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  sigset_t stop_signals, none, previous;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  sigemptyset(&none);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  // A group of its own (what the handler stops), default SIGINT/SIGTERM actions, nothing blocked.
  posix_spawnattr_setpgroup(&attributes, 0);
  posix_spawnattr_setsigdefault(&attributes, &stop_signals);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setflags(&attributes,
                           POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  // Blocked on this thread until the child is registered: a signal handled in between would
  // leave it running (one taken by a worker thread in that instant still can).
  pthread_sigmask(SIG_BLOCK, &stop_signals, &previous);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, argv[0], &actions, &attributes, argv.data(), environ);
  if (spawned == 0) running_child.store(pid);
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  posix_spawnattr_destroy(&attributes);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    std::error_code ignored;
    std::filesystem::remove(partial_log, ignored);
    write_output_file(log,
                      fmt::format("cannot run {}: {}\n", args.front(), std::strerror(spawned)));
    return 127;
  }
  int status = 0;
  pid_t waited = -1;
  do {
    waited = ::waitpid(pid, &status, 0);
  } while (waited < 0 && errno == EINTR);
  running_child.store(0);
  std::error_code ec;
  std::filesystem::rename(partial_log, log, ec);
  if (waited < 0) return 128;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
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
