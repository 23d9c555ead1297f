// The paper's and the reference's numbers, read from the data files in <share>/data/report.
#include <fstream>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/core/share_dir.hpp"
#include "report.hpp"

namespace implicit::app::report {

using nlohmann::json;

json read_numbers_file(const std::filesystem::path& file,
                       const std::vector<std::string>& required) {
  std::ifstream in(file);
  if (!in)
    throw InvalidArgument(fmt::format(
        "{}: cannot open the report's numbers file (set IMPLICIT_DATA_DIR to the folder that "
        "holds report/{})",
        file.string(), file.filename().string()));
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    throw ParseError(fmt::format("{}: not valid JSON ({})", file.string(), e.what()));
  }
  if (!j.is_object())
    throw ParseError(
        fmt::format("{}: expected a JSON object, got {}", file.string(), printable(j.dump(), 40)));
  if (!j.contains("source") || !j["source"].is_string())
    throw ParseError(fmt::format("{}: expected a \"source\" string", file.string()));
  for (const auto& key : required)
    if (!j.contains(key) || !j[key].is_object())
      throw ParseError(fmt::format("{}: expected an object \"{}\"", file.string(), key));
  return j;
}

namespace {

std::filesystem::path numbers_file(const char* name) {
  return find_share_dir("data", "IMPLICIT_DATA_DIR") / "report" / name;
}

}  // namespace

json paper_numbers() {
  return read_numbers_file(numbers_file("paper.json"), {"table2", "table4", "table5", "table6"});
}

json reference_numbers() {
  return read_numbers_file(numbers_file("reference.json"),
                           {"table2", "arm", "himmelblau", "table5", "table6"});
}

}  // namespace implicit::app::report
