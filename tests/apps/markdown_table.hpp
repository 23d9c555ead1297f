#pragma once
// The rows of a Markdown table in a doc of the repository, for the tests that check a table of
// the docs against the registry it describes.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace implicit::test {

/// The body rows of the table whose header line is `header` in `doc` (a path under the
/// repository's root), in order; empty when the doc or the table is missing.
inline std::vector<std::string> markdown_table_rows(const std::string& doc,
                                                    const std::string& header) {
  std::ifstream in(std::filesystem::path(IMPLICIT_SOURCE_DIR) / doc);
  std::vector<std::string> rows;
  bool in_table = false;
  for (std::string line; std::getline(in, line);) {
    if (line == header)
      in_table = true;
    else if (in_table && !line.starts_with("|"))
      in_table = false;
    else if (in_table && !line.starts_with("|---"))
      rows.push_back(line);
  }
  return rows;
}

}  // namespace implicit::test
