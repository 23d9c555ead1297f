// The paper's and the reference's numbers and the report's text, read from the data files in
// <share>/data/report.
#include <fstream>

#include <fmt/format.h>

#include "implicit/core/error.hpp"
#include "implicit/core/share_dir.hpp"
#include "json_input.hpp"
#include "report.hpp"

namespace implicit::app::report {

using nlohmann::json;

namespace {

/// A data file's JSON object; `what` says which file it is in the error when it cannot be opened.
json read_object(const std::filesystem::path& file, const char* what) {
  std::ifstream in(file);
  if (!in)
    throw InvalidArgument(fmt::format(
        "{}: cannot open the report's {} file (set IMPLICIT_DATA_DIR to the folder that "
        "holds report/{})",
        file.string(), what, file.filename().string()));
  json j;
  try {
    j = parse_json_bounded(in, file);
  } catch (const json::parse_error& e) {
    throw ParseError(fmt::format("{}: not valid JSON ({})", file.string(), e.what()));
  }
  if (!j.is_object())
    throw ParseError(
        fmt::format("{}: expected a JSON object, got {}", file.string(), printable(j.dump(), 40)));
  return j;
}

}  // namespace

json read_numbers_file(const std::filesystem::path& file,
                       const std::vector<std::string>& required) {
  json j = read_object(file, "numbers");
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

bool is_text(const json& value) {
  if (value.is_string()) return true;
  if (!value.is_array() || value.empty()) return false;
  for (const auto& piece : value)
    if (!piece.is_string()) return false;
  return true;
}

}  // namespace

json paper_numbers() {
  return read_numbers_file(numbers_file("paper.json"), {"table2", "table4", "table5", "table6"});
}

json reference_numbers() {
  return read_numbers_file(numbers_file("reference.json"),
                           {"table2", "arm", "himmelblau", "table5", "table6"});
}

// ---- Text -------------------------------------------------------------------------------------

Text::Text(json strings, std::filesystem::path file)
    : strings_(std::make_shared<const json>(std::move(strings))),
      file_(std::move(file)),
      used_(std::make_shared<std::set<std::string>>()) {}

std::string Text::operator()(const std::string& key) const {
  if (!strings_ || !strings_->contains(key))
    throw ParseError(fmt::format("{}: no text \"{}\" (the report needs it)", file_.string(), key));
  used_->insert(key);
  const json& value = strings_->at(key);
  if (value.is_string()) return value.get<std::string>();
  std::string joined;
  for (std::size_t i = 0; i < value.size(); ++i) {
    if (i > 0) joined += ' ';
    joined += value[i].get_ref<const std::string&>();
  }
  return joined;
}

std::vector<std::string> Text::items(const std::string& key) const {
  std::vector<std::string> list{(*this)(key + ".1")};
  for (int i = 2; strings_->contains(fmt::format("{}.{}", key, i)); ++i)
    list.push_back((*this)(fmt::format("{}.{}", key, i)));
  return list;
}

std::vector<std::string> Text::keys() const {
  std::vector<std::string> all;
  if (strings_)
    for (const auto& [key, value] : strings_->items()) all.push_back(key);
  return all;
}

void Text::bad_placeholder(const std::string& key, const std::string& what) const {
  throw ParseError(
      fmt::format("{}: text \"{}\" cannot be formatted ({})", file_.string(), key, what));
}

Text read_text_file(const std::filesystem::path& file) {
  json j = read_object(file, "text");
  for (const auto& [key, value] : j.items())
    if (!is_text(value))
      throw ParseError(fmt::format("{}: text \"{}\": expected a string or an array of strings",
                                   file.string(), key));
  return Text(std::move(j), file);
}

Text report_text() { return read_text_file(numbers_file("text.json")); }

}  // namespace implicit::app::report
