#pragma once
// The record of one finished run, as `--resume` keeps it in <out>/.resume/
// (apps/parallel_runs.hpp): the run's key, the count, then one number per line in hexadecimal
// floating point (exact, NaN and inf too). Separate from parallel_runs.cpp so that the fuzz target
// reads records alone.

#include <string>
#include <vector>

namespace implicit::app {

using RunRecord = std::vector<double>;

/// The text of the record of `r` under `key` (one line, no newline in it).
std::string format_run_record(const std::string& key, const RunRecord& r);

/// Reads `text` as a record of `key` into `r`. Returns why it is not one ("got an empty file",
/// "expected 6 numbers, got 'x' on line 3", ...), empty when it is; never throws for any text.
/// At most 2^20 numbers: a bound, so that an edited count cannot exhaust memory.
std::string parse_run_record(const std::string& text, const std::string& key, RunRecord& r);

}  // namespace implicit::app
