#pragma once
// --trajectory and --truth-trajectory on the command line: the TUM writer of the experiments
// layer (experiments/tum_output.hpp) and the flags' check.
#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

#include "experiments/tum_output.hpp"

namespace implicit::app {

using experiments::TumTrack;

/// The check of --trajectory and --truth-trajectory, before any run: a name, in a folder that
/// exists (a long run must not end in "cannot write" for a typing error).
inline CLI::Validator tum_file_validator() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text.empty()) return "expected a file name, got an empty one";
        const std::filesystem::path folder = std::filesystem::path(text).parent_path();
        std::error_code ec;
        if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
          return "expected a file in an existing folder, got '" + text + "' (no folder '" +
                 folder.string() + "')";
        return {};
      },
      "FILE");
}

}  // namespace implicit::app
