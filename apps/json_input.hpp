#pragma once
// JSON from files a user can name (results.json for `reproduce --report-only`, the report's data
// files under IMPLICIT_DATA_DIR), parsed with a bound on its nesting depth. nlohmann::json parses
// and destroys without recursion, but dump(), copies, comparisons and walkers such as
// check_number_ranges (results_file.cpp) recurse once per level: a results.json nested 20 000
// levels deep overflowed the stack. Refusing such a file while it is parsed bounds every later
// walk at once.
#include <filesystem>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "implicit/core/error.hpp"

namespace implicit::app {

/// Arrays and objects nested deeper than this are refused: far beyond any file the project
/// writes (results.json has 7 levels), far below what recursion over it can take.
inline constexpr int kMaxJsonDepth = 64;

/// nlohmann::json::parse(input), which throws implicit::ParseError naming `file`, the limit and
/// the level when an array or object opens more than kMaxJsonDepth levels deep. Malformed JSON
/// throws nlohmann::json::parse_error as parse() does.
template <typename Input>
nlohmann::json parse_json_bounded(Input&& input, const std::filesystem::path& file) {
  using Event = nlohmann::json::parse_event_t;
  // `depth` counts the containers around the one that opens: the top level has depth 0.
  const nlohmann::json::parser_callback_t bound = [&file](int depth, Event event,
                                                          const nlohmann::json&) {
    if ((event == Event::object_start || event == Event::array_start) && depth >= kMaxJsonDepth)
      throw ParseError(fmt::format(
          "{}: expected JSON nested at most {} levels deep, got an array or object at level {}",
          file.string(), kMaxJsonDepth, depth + 1));
    return true;
  };
  return nlohmann::json::parse(std::forward<Input>(input), bound);
}

}  // namespace implicit::app
