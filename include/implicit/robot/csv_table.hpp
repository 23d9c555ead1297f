#pragma once
// A strict reader for numeric CSV files with a header line (the Car Park files and similar).
//
//   auto t = read_numeric_csv("data/carpark/carpark_gps.csv", {"time_s", "east_m", "north_m"});
//   double e = t.at(row, 1);
//   require_increasing(t, 0);            // time column strictly increasing
//
// Every problem is a ParseError naming the file, the line (1-based, the header is line 1) and the
// field: a missing or renamed column, a row with too few or too many fields, a field that is not a
// finite number (NaN and inf are rejected), an empty file. Files may be gzip-compressed
// (read_text_file): `carpark_dr.csv` is read from `carpark_dr.csv.gz` when only that exists.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace implicit::robot {

struct NumericTable {
  std::string file;                 ///< path, for messages
  std::vector<std::string> header;  ///< column names
  std::size_t rows = 0;
  std::size_t cols = 0;
  std::vector<double> values;      ///< row-major rows x cols
  std::vector<std::size_t> lines;  ///< file line of each data row (blank lines are skipped)

  double at(std::size_t row, std::size_t col) const { return values[row * cols + col]; }
  /// Line number of a data row in the file (header = line 1).
  std::size_t line_of(std::size_t row) const { return lines[row]; }
};

/// `path` if it exists, else `path` + ".gz" if that exists (so a data folder may hold its large
/// files compressed under the same names), else `path` unchanged (the reader reports it missing).
std::filesystem::path resolve_data_file(const std::filesystem::path& path);

/// The whole content of a text file, decompressed when it is gzip-compressed (detected from the
/// content, any name; missing files are looked up as `path`.gz too, see resolve_data_file).
/// Throws ParseError "file:line: expected a complete gzip stream, got corrupt or truncated data
/// ..." for a damaged gzip file (line = where the readable text stops), or when it cannot be
/// opened. Used by every reader of robot/ (CSV tables, the robot log).
/// Files larger than max_bytes (decompressed) are refused with a ParseError: a bound, so that
/// `--data /dev/zero` or a decompression bomb ends in a message, not the OOM killer.
inline constexpr std::size_t kMaxTextFileBytes = std::size_t{256} << 20;
std::string read_text_file(const std::filesystem::path& path,
                           std::size_t max_bytes = kMaxTextFileBytes);

/// Writes `text` to `path`, gzip-compressed when the name ends in ".gz", under a temporary name
/// renamed when complete (OutputFile, implicit/core/output_file.hpp): never half a file under the
/// final name. Throws InvalidArgument naming the file when it cannot be written completely.
void write_text_file(const std::filesystem::path& path, const std::string& text);

/// Reads a CSV whose header must equal `expected_header` exactly (gzip accepted, see
/// read_text_file).
NumericTable read_numeric_csv(const std::filesystem::path& path,
                              const std::vector<std::string>& expected_header);

/// Throws ParseError (file, line, field) unless column `col` is strictly increasing.
void require_increasing(const NumericTable& table, std::size_t col);

}  // namespace implicit::robot
