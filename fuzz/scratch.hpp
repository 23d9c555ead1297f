#pragma once
// What the fuzz targets share: most readers take a path (a folder of CSV files, a gzip file), so
// an input is written to a private scratch folder first, and an input holding several files is
// split at lines "%%" (the seed corpus in fuzz/corpus/ uses the same layout, so that a mutation
// can reach every file and the readers see them together, as they do in data/).

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

namespace implicit::fuzz {

/// A folder of this process (libFuzzer's -jobs run several), removed at exit.
class ScratchDir {
 public:
  ScratchDir()
      : path_(std::filesystem::temp_directory_path() /
              ("implicit-fuzz-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const { return path_; }

  /// Writes `content` to `name` in the folder (creating subfolders) and returns its path.
  std::filesystem::path write(const std::filesystem::path& name, std::string_view content) const {
    const auto file = path_ / name;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    return file;
  }

 private:
  std::filesystem::path path_;
};

inline const ScratchDir& scratch() {
  static const ScratchDir dir;
  return dir;
}

/// The input as text.
inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// Splits `text` into exactly `count` files at lines "%%"; missing files are empty, and the last
/// file keeps any further separators.
inline std::vector<std::string_view> split_files(std::string_view text, std::size_t count) {
  constexpr std::string_view kSeparator = "\n%%\n";
  std::vector<std::string_view> files;
  while (files.size() + 1 < count) {
    const auto at = text.find(kSeparator);
    if (at == std::string_view::npos) break;
    files.push_back(text.substr(0, at + 1));  // the file keeps its last newline
    text.remove_prefix(at + kSeparator.size());
  }
  files.push_back(text);
  files.resize(count);
  return files;
}

}  // namespace implicit::fuzz
