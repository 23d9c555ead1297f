// Fuzz target: a --resume record (experiments/run_record.hpp) as distribute_runs reads it from
// <out>/.resume/: the first line of the input is taken as the expected key, so both the key check
// and the numbers are reached.
//
// parse_run_record must return a reason for any text, never throw; a record it accepts must be
// written back and read again to the same numbers, bit for bit (the records are exact). Anything
// else (an exception, a crash, a sanitizer report, a hang, a different number) is a finding.

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>

#include "experiments/run_record.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::string key = text.substr(0, text.find('\n'));
  implicit::experiments::RecordValues record;
  if (!implicit::experiments::parse_run_record(text, key, record).empty()) return 0;
  implicit::experiments::RecordValues again;
  if (!implicit::experiments::parse_run_record(
           implicit::experiments::format_run_record(key, record), key, again)
           .empty() ||
      again.size() != record.size())
    std::abort();
  for (std::size_t i = 0; i < record.size(); ++i)
    if (std::memcmp(&record[i], &again[i], sizeof(double)) != 0 &&
        !(record[i] != record[i] && again[i] != again[i]))  // NaN payloads need not survive
      std::abort();
  return 0;
}
