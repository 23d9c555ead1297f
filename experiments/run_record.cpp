#include "experiments/run_record.hpp"

#include <cstdlib>
#include <sstream>

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit::experiments {

std::string format_run_record(const std::string& key, const RecordValues& r) {
  std::string text = key + "\n" + fmt::format("{}\n", r.size());
  for (const double v : r) text += fmt::format("{:a}\n", v);
  return text;
}

std::string parse_run_record(const std::string& text, const std::string& key, RecordValues& r) {
  if (text.empty()) return "got an empty file";
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line != key)
    return fmt::format("expected the first line '{}', got '{}'", printable(key), printable(line));
  constexpr std::size_t kMaxValues = std::size_t{1} << 20;
  const bool digits = std::getline(in, line) && !line.empty() && line.size() <= 18 &&
                      line.find_first_not_of("0123456789") == std::string::npos;
  const std::size_t count = digits ? std::strtoull(line.c_str(), nullptr, 10) : 0;
  if (!digits || count > kMaxValues)
    return fmt::format("expected a count of numbers in [0, {}] on line 2, got '{}'", kMaxValues,
                       printable(line));
  r.assign(count, 0.0);
  for (std::size_t k = 0; k < count; ++k) {
    const bool got = static_cast<bool>(std::getline(in, line));
    char* end = nullptr;
    if (got && !line.empty() && line.find_first_of(" \t") == std::string::npos)
      r[k] = std::strtod(line.c_str(), &end);
    if (!got || end == nullptr || *end != '\0')
      return fmt::format("expected {} numbers, got {} on line {}", count,
                         got ? fmt::format("'{}'", printable(line)) : std::string("the end"),
                         k + 3);
  }
  if (std::getline(in, line))
    return fmt::format("expected {} numbers, got more on line {}: '{}'", count, count + 3,
                       printable(line));
  return {};
}

}  // namespace implicit::experiments
