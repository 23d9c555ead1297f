#pragma once
// Subcommands register themselves here (one static Registrar per apps/cmd_*.cpp file), so the
// tool's main() does not need to know them.
//
//   static implicit::app::Registrar reg{"slit", "Double slit (paper Table 2)",
//                                       [](CLI::App& sub) { ... sub.callback(...); }};

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace implicit::app {

struct Subcommand {
  std::string name;
  std::string description;
  std::function<void(CLI::App&)> setup;  ///< adds options and a callback to the subcommand
};

std::vector<Subcommand>& subcommands();

struct Registrar {
  Registrar(std::string name, std::string description, std::function<void(CLI::App&)> setup) {
    subcommands().push_back({std::move(name), std::move(description), std::move(setup)});
  }
};

}  // namespace implicit::app
