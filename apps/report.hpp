#pragma once
// The reproduction report of `implicit reproduce`: the paper's numbers and ours side by side.
//
// Everything in the report is derived from one JSON object, the content of DIR/results.json
// (build, machine, settings, one entry per experiment configuration, figure statuses). So a
// report can be rebuilt from a results.json alone (`implicit reproduce --report-only`), and a
// reader can check every number in it.
//
//   nlohmann::json results = ...;                      // as written by `implicit reproduce`
//   report::Document doc = report::build_report(results, dir);
//   write_text(dir / "report.md", doc.markdown());
//   write_text(dir / "report.html", doc.html("Reproduction report"));
//
// The document model is deliberately small (headings, paragraphs, lists, tables, images, code)
// so that Markdown and self-contained HTML come from the same blocks and cannot disagree.
// Inline markup in text: `code` and **bold** only.

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace implicit::app::report {

struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::string caption;  ///< shown above the table
};

struct Block {
  enum class Kind { kHeading, kParagraph, kList, kTable, kImage, kCode };
  Kind kind = Kind::kParagraph;
  int level = 1;                   ///< heading level (1..4)
  std::string text;                ///< heading, paragraph, code, image alt text
  std::string src;                 ///< image file, relative to the report
  std::vector<std::string> items;  ///< list items
  Table table;
};

class Document {
 public:
  void heading(int level, std::string text);
  void paragraph(std::string text);
  void list(std::vector<std::string> items);
  void table(Table t);
  void image(std::string src, std::string caption);
  void code(std::string text);

  std::string markdown() const;
  /// One self-contained HTML page (inline CSS, no scripts); images are referenced by file name.
  std::string html(const std::string& title) const;
  const std::vector<Block>& blocks() const { return blocks_; }

 private:
  std::vector<Block> blocks_;
};

/// Escapes &, <, >, " for HTML text and attributes.
std::string html_escape(const std::string& s);

// ---- Numbers ----------------------------------------------------------------------------------

/// "12.3" with `digits` decimals; "–" when the value is missing, null or not a number.
std::string number(const nlohmann::json& value, int digits);
/// "mean ± sd (median m)" from three keys of an experiment result (median left out if missing).
std::string spread(const nlohmann::json& result, const std::string& prefix, int digits);

// ---- Reference numbers ------------------------------------------------------------------------

/// The paper's Tables 2, 4, 5, 6 (and the numbers its text quotes), transcribed, plus the
/// independent reference values of the corrected specification. Stored in results.json under
/// "paper" and "reference" so that figure scripts can draw them too.
nlohmann::json paper_numbers();
nlohmann::json reference_numbers();

// ---- The report -------------------------------------------------------------------------------

/// Builds the whole report from results.json's content. `dir` is the output folder (to embed
/// CSV tables written by the experiments, e.g. table4_himmelblau.csv, when present).
Document build_report(const nlohmann::json& results, const std::filesystem::path& dir);

/// Writes the side-by-side tables as CSV (table2_slit.csv, table5_mcl.csv, table6_slam.csv)
/// into `dir`; returns the file names written. Rows exist only for configurations that ran.
std::vector<std::string> write_table_csvs(const nlohmann::json& results,
                                          const std::filesystem::path& dir);

/// Reads a small CSV file (comma-separated, no quoting) into a table; throws ParseError naming
/// the file and line when a row has the wrong number of fields.
Table read_csv_table(const std::filesystem::path& file);

/// The configurations of one experiment in results.json ("runs" array), possibly empty.
const nlohmann::json& experiment_runs(const nlohmann::json& results, const std::string& name);

}  // namespace implicit::app::report
