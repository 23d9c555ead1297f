// Reading text data files that may be gzip-compressed (see csv_table.hpp, read_text_file).
#include <zlib.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/core/output_file.hpp"
#include "implicit/robot/csv_table.hpp"

namespace implicit::robot {

std::filesystem::path resolve_data_file(const std::filesystem::path& path) {
  if (std::filesystem::exists(path) || path.extension() == ".gz") return path;
  std::filesystem::path gz = path;
  gz += ".gz";
  return std::filesystem::exists(gz) ? gz : path;
}

std::string read_text_file(const std::filesystem::path& requested, std::size_t max_bytes) {
  const std::filesystem::path path = resolve_data_file(requested);
  const std::string name = path.string();
  if (std::filesystem::is_directory(path))
    throw ParseError(fmt::format("{}: expected a text file, got a directory", name));
  // gzopen reads plain files transparently, so one code path serves both; the format is
  // detected from the gzip magic bytes, not from the name.
  gzFile f = gzopen(name.c_str(), "rb");
  if (f == nullptr) throw ParseError(fmt::format("{}: cannot open the file for reading", name));
  gzbuffer(f, 1 << 17);
  std::string text;
  std::array<char, 1 << 16> buf{};
  int got = 0;
  while ((got = gzread(f, buf.data(), static_cast<unsigned>(buf.size()))) > 0) {
    // A bound, so that /dev/zero or a decompression bomb is an error, not the OOM killer.
    if (text.size() + static_cast<std::size_t>(got) > max_bytes) {
      gzclose(f);
      throw ParseError(fmt::format(
          "{}:{}: expected at most {:g} MiB of text, got more (not a data file of this project?)",
          name, 1 + std::count(text.begin(), text.end(), '\n'), max_bytes / 1048576.0));
    }
    text.append(buf.data(), static_cast<std::size_t>(got));
  }
  int err = Z_OK;
  const std::string message = gzerror(f, &err);
  const int closed = gzclose(f);
  if (got < 0 || (err != Z_OK && err != Z_STREAM_END) || closed != Z_OK) {
    // The line where the readable data stop: where a parser would have been when it failed.
    const auto line = 1 + std::count(text.begin(), text.end(), '\n');
    throw ParseError(fmt::format(
        "{}:{}: expected a complete gzip stream, got corrupt or truncated data after {} "
        "decompressed bytes (zlib: {})",
        name, line, text.size(), message.empty() ? fmt::format("code {}", closed) : message));
  }
  return text;
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  // Under a temporary name, renamed when complete (gzip for a .gz name): a killed process or a
  // full disk never leaves half a log under the final name.
  write_output_file(path, text, "");
}

}  // namespace implicit::robot
