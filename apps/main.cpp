// The `implicit` command-line tool: one subcommand per experiment of the paper, and `reproduce`.
// Exit codes (docs/cli.md): 0 success; 1 an error (message on stderr); 2 bad command line
// (unknown flag, bad value: CLI11 names the flag and the accepted range); 3 `reproduce` wrote its
// report but at least one experiment or figure failed.

#include <algorithm>
#include <cstdio>
#include <exception>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "context.hpp"
#include "experiments/parallel_runs.hpp"
#include "implicit/core/version.hpp"
#include "registry.hpp"

namespace implicit::app {
std::vector<Subcommand>& subcommands() {
  static std::vector<Subcommand> list;
  return list;
}
}  // namespace implicit::app

namespace {
int run_command(int argc, char** argv) {
  using namespace implicit::app;
  CLI::App app{
      "implicit: implicit sampling for path integral control, Monte Carlo localization "
      "and SLAM"};
  app.require_subcommand(0, 1);
  app.set_version_flag("--version", fmt::format("implicit {} (commit {})", implicit::version(),
                                                implicit::git_commit()));
  auto& list = subcommands();
  std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  for (auto& s : list) {
    CLI::App* sub = app.add_subcommand(s.name, s.description);
    s.setup(*sub);
    // Every subcommand shows at least one example, even before its owner writes better ones.
    if (sub->get_footer().empty())
      set_examples(*sub, {fmt::format("implicit {} --json", s.name),
                          fmt::format("implicit {} --seed 7 --out out/{}", s.name, s.name)});
  }
  // Set after the subcommands exist: CLI11 copies a parent's footer into each new subcommand,
  // which would show these examples in place of the subcommand's own.
  app.footer(
      "\nExamples:\n"
      "  implicit reproduce --quick --out out   # every table and figure, reduced settings\n"
      "  implicit slit --samples 50 --json      # one experiment, result as JSON\n"
      "  implicit <subcommand> --help           # options of one subcommand\n"
      "\nExit codes: 0 success, 1 error, 2 bad command line, 3 report written but an experiment "
      "or figure failed.\n");
  install_signal_handlers();
  try {
    app.parse(argc, argv);
    if (app.get_subcommands().empty()) {
      // Nothing to do is a usage error (scripts should not mistake it for a run).
      fmt::print(stderr, "{}", app.help());
      return 2;
    }
  } catch (const CLI::RuntimeError& e) {
    // Thrown by a subcommand to choose its exit code after reporting on stderr itself.
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "implicit: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  // Under an MPI launcher every rank runs the command; see experiments/parallel_runs.hpp.
  implicit::experiments::RankSession session(argc, argv);
  return session.finish(run_command(session.argc(), session.argv()));
}
