#pragma once
// The repository's data folder (the Car Park scenario), for the SLAM tests that load it.
#include <filesystem>

namespace implicit::slam {

inline std::filesystem::path repository_data_dir() {
  return std::filesystem::path(IMPLICIT_SOURCE_DIR) / "data";
}

}  // namespace implicit::slam
