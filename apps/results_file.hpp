#pragma once
// results.json as `implicit reproduce --report-only` reads it back: parsed, checked to be an
// earlier run's (its schema and an "experiments" object), and every floating-point number
// bounded, so that the report can read counts as integers without overflow. The fuzz target
// fuzz/fuzz_results_json.cpp goes through the same function.

#include <filesystem>
#include <string_view>

#include <nlohmann/json.hpp>

namespace implicit::app {

/// Parses `text` (the contents of `file`, named in errors) as a results.json. Throws
/// implicit::ParseError naming the file for malformed JSON, nesting deeper than kMaxJsonDepth
/// (json_input.hpp), a number beyond a double, another program's JSON, or a number out of range
/// (naming its JSON pointer).
nlohmann::json parse_results(std::string_view text, const std::filesystem::path& file);

/// Reads and parses `file` as above; throws implicit::InvalidArgument if it cannot be read.
nlohmann::json read_results(const std::filesystem::path& file);

}  // namespace implicit::app
