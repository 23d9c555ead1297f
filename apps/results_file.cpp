#include "results_file.hpp"

#include <cmath>
#include <string>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/robot/csv_table.hpp"
#include "json_input.hpp"

namespace implicit::app {
namespace {

using nlohmann::json;

/// Floating-point values must lie within +-2^31: the report reads counts (runs, particles) as
/// int, and converting a larger double to int is undefined behaviour. No run writes more.
/// One recursion per level: `depth` stops it at the parser's bound (json_input.hpp), so that a
/// document that did not come through parse_json_bounded cannot overflow the stack either.
void check_number_ranges(const json& value, const std::string& where,
                         const std::filesystem::path& file, int depth = 0) {
  constexpr double kLimit = 2147483648.0;
  if (depth > kMaxJsonDepth)
    throw ParseError(fmt::format("{}: expected JSON nested at most {} levels deep, got more at {}",
                                 file.string(), kMaxJsonDepth, printable(where, 60)));
  if (value.is_number_float() && !(std::abs(value.get<double>()) < kLimit))
    throw ParseError(fmt::format("{}: the number at {} is {}, out of range (|x| < 2^31)",
                                 file.string(), where.empty() ? "/" : where, value.dump()));
  if (value.is_object())
    for (const auto& [key, item] : value.items())
      check_number_ranges(item, where + "/" + key, file, depth + 1);
  if (value.is_array())
    for (std::size_t i = 0; i < value.size(); ++i)
      check_number_ranges(value[i], where + "/" + std::to_string(i), file, depth + 1);
}

}  // namespace

json parse_results(std::string_view text, const std::filesystem::path& file) {
  json results;
  try {
    results = parse_json_bounded(text, file);
  } catch (const json::exception& e) {
    // parse_error, or out_of_range for a number beyond a double (1e999)
    throw ParseError(fmt::format("{}: {}", file.string(), e.what()));
  }
  // `{}` or another program's JSON is not an earlier run: say so instead of an empty report.
  if (!results.is_object() || results.value("schema", json()) != "implicit-reproduce-1" ||
      !results.contains("experiments") || !results["experiments"].is_object())
    throw ParseError(
        fmt::format("{}: expected the results.json of `implicit reproduce` (\"schema\": "
                    "\"implicit-reproduce-1\" and an \"experiments\" object), got {}",
                    file.string(), printable(results.dump(), 60)));
  check_number_ranges(results, "", file);
  return results;
}

json read_results(const std::filesystem::path& file) {
  if (!std::filesystem::is_regular_file(file))
    throw InvalidArgument(fmt::format(
        "--report-only: expected {} from an earlier run, got no such file", file.string()));
  // Bounded, like every data file (robot::read_text_file refuses more than 256 MiB).
  return parse_results(robot::read_text_file(file), file);
}

}  // namespace implicit::app
