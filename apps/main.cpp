// The `implicit` command-line tool: one subcommand per experiment of the paper, and `reproduce`.
// Exit codes: 0 success, 1 an experiment failed, 2 bad command line (CLI11's usage errors).

#include <algorithm>
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "implicit/core/version.hpp"
#include "registry.hpp"

namespace implicit::app {
std::vector<Subcommand>& subcommands() {
  static std::vector<Subcommand> list;
  return list;
}
}  // namespace implicit::app

int main(int argc, char** argv) {
  using namespace implicit::app;
  CLI::App app{"implicit: implicit sampling for path integral control, Monte Carlo localization "
               "and SLAM"};
  app.require_subcommand(0, 1);
  app.set_version_flag("--version",
                       fmt::format("implicit {} (commit {})", implicit::version(),
                                   implicit::git_commit()));
  auto& list = subcommands();
  std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  for (auto& s : list) s.setup(*app.add_subcommand(s.name, s.description));
  try {
    app.parse(argc, argv);
    if (app.get_subcommands().empty()) {
      fmt::print("{}", app.help());
      return 0;
    }
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    fmt::print(stderr, "implicit: error: {}\n", e.what());
    return 1;
  }
  return 0;
}
