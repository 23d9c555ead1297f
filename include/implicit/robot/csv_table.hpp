#pragma once
// A strict reader for numeric CSV files with a header line (the Car Park files and similar).
//
//   auto t = read_numeric_csv("data/carpark/carpark_gps.csv", {"time_s", "east_m", "north_m"});
//   double e = t.at(row, 1);
//   require_increasing(t, 0);            // time column strictly increasing
//
// Every problem is a ParseError naming the file, the line (1-based, the header is line 1) and the
// field: a missing or renamed column, a row with too few or too many fields, a field that is not a
// finite number (NaN and inf are rejected), an empty file.

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

/// Reads a CSV whose header must equal `expected_header` exactly.
NumericTable read_numeric_csv(const std::filesystem::path& path,
                              const std::vector<std::string>& expected_header);

/// Throws ParseError (file, line, field) unless column `col` is strictly increasing.
void require_increasing(const NumericTable& table, std::size_t col);

}  // namespace implicit::robot
