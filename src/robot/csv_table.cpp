#include "implicit/robot/csv_table.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string_view>

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit::robot {
namespace {

std::vector<std::string_view> split(std::string_view line, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t pos = line.find(sep, start);
    if (pos == std::string_view::npos) {
      out.push_back(line.substr(start));
      return out;
    }
    out.push_back(line.substr(start, pos - start));
    start = pos + 1;
  }
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

}  // namespace

NumericTable read_numeric_csv(const std::filesystem::path& path,
                              const std::vector<std::string>& expected_header) {
  const std::filesystem::path resolved = resolve_data_file(path);
  std::istringstream in(read_text_file(resolved));
  NumericTable t;
  t.file = resolved.string();
  std::string line;
  if (!std::getline(in, line))
    throw ParseError(fmt::format("{}:1: expected a header line, got an empty file", t.file));
  for (std::string_view name : split(trim(line), ',')) t.header.emplace_back(trim(name));
  for (std::size_t c = 0; c < expected_header.size(); ++c) {
    if (c >= t.header.size())
      throw ParseError(fmt::format("{}:1: missing column '{}' (expected {} columns, got {})",
                                   t.file, expected_header[c], expected_header.size(),
                                   t.header.size()));
    if (t.header[c] != expected_header[c])
      throw ParseError(fmt::format("{}:1: column {}: expected '{}', got '{}'", t.file, c + 1,
                                   expected_header[c], printable(t.header[c])));
  }
  if (t.header.size() != expected_header.size())
    throw ParseError(fmt::format("{}:1: expected {} columns, got {} (extra column '{}')", t.file,
                                 expected_header.size(), t.header.size(),
                                 printable(t.header[expected_header.size()])));
  t.cols = t.header.size();
  std::size_t line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string_view row = trim(line);
    if (row.empty()) continue;
    const auto fields = split(row, ',');
    if (fields.size() != t.cols)
      throw ParseError(
          fmt::format("{}:{}: expected {} fields, got {}", t.file, line_no, t.cols, fields.size()));
    for (std::size_t c = 0; c < t.cols; ++c) {
      const std::string field(trim(fields[c]));
      char* end = nullptr;
      const double v = std::strtod(field.c_str(), &end);
      if (field.empty() || end != field.c_str() + field.size() || !std::isfinite(v))
        throw ParseError(fmt::format("{}:{}: field '{}': expected a finite number, got '{}'",
                                     t.file, line_no, t.header[c], printable(field)));
      t.values.push_back(v);
    }
    t.lines.push_back(line_no);
    ++t.rows;
  }
  if (t.rows == 0) throw ParseError(fmt::format("{}:2: expected data rows, got none", t.file));
  return t;
}

void require_increasing(const NumericTable& t, std::size_t col) {
  for (std::size_t r = 1; r < t.rows; ++r)
    if (!(t.at(r, col) > t.at(r - 1, col)))
      throw ParseError(
          fmt::format("{}:{}: field '{}': expected a time after {}, got {} (times must "
                      "increase)",
                      t.file, t.line_of(r), t.header[col], t.at(r - 1, col), t.at(r, col)));
}

}  // namespace implicit::robot
