// Fuzz target: results.json as `implicit reproduce --report-only` reads it (apps/results_file.cpp,
// apps/report.cpp, apps/report_content.cpp): parse and check, build the report, render Markdown and
// HTML, write the tables.
//
// Malformed or wrongly typed JSON must end in an exception that `implicit` turns into an error
// message and exit 1: ParseError, InvalidArgument, or one of nlohmann::json's own exceptions.
// Anything else (std::bad_alloc, another exception, a crash, a sanitizer report, a hang) is a
// finding.

#include <cstdint>
#include <cstdlib>
#include <string_view>

#include <nlohmann/json.hpp>

#include "implicit/core/error.hpp"
#include "report.hpp"
#include "results_file.hpp"
#include "scratch.hpp"

// The report's paper and reference numbers come from the bundled data files (data/report/).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  setenv("IMPLICIT_DATA_DIR", IMPLICIT_FUZZ_DATA_DIR, 0);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace report = implicit::app::report;
  nlohmann::json results;
  try {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    results = implicit::app::parse_results(text, "results.json");
  } catch (const implicit::ParseError&) {  // what --report-only reports and exits 1 for
    return 0;
  }
  const auto& dir = implicit::fuzz::scratch().path();
  try {
    const report::Document doc = report::build_report(results, dir / "report");
    (void)doc.markdown();
    (void)doc.html("Reproduction report");
    report::write_table_csvs(results, dir / "tables");
  } catch (const implicit::ParseError&) {
  } catch (const implicit::InvalidArgument&) {
  } catch (const nlohmann::json::exception&) {
  }
  return 0;
}
