#pragma once
// The reproduction report of `implicit reproduce`: the paper's numbers and ours side by side.
//
// Everything in the report is derived from one JSON object, the content of DIR/results.json
// (build, machine, settings, one entry per experiment configuration, figure statuses). So a
// report can be rebuilt from a results.json alone (`implicit reproduce --report-only`), and a
// reader can check every number in it. Its words are data too (data/report/text.json, `Text`).
//
//   nlohmann::json results = ...;                      // as written by `implicit reproduce`
//   report::Document doc = report::build_report(results, dir);
//   write_text(dir / "report.md", doc.markdown());
//   write_text(dir / "report.html", doc.html(doc.title()));
//
// The document model is deliberately small (headings, paragraphs, lists, tables, images, code)
// so that Markdown and self-contained HTML come from the same blocks and cannot disagree.
// Inline markup in text: `code` and **bold** only.

#include <filesystem>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
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
  /// The title of the HTML page (`html(doc.title())`).
  void set_title(std::string title) { title_ = std::move(title); }
  const std::string& title() const { return title_; }

 private:
  std::vector<Block> blocks_;
  std::string title_;
};

/// Escapes &, <, >, " for HTML text and attributes.
std::string html_escape(const std::string& s);

// ---- Plain-text tables (the command line's summaries) -----------------------------------------

/// The width of UTF-8 text on a terminal: its code points, so that "–" and "±" count as one.
std::size_t text_width(const std::string& s);
/// `rows` as lines of columns, each padded to its widest cell (text_width) and two spaces apart,
/// after `indent`; column j is right-aligned when right[j] (numbers), else left-aligned. Rows may
/// have fewer cells than others; no line ends in blanks.
///   aligned_columns({{"slit", "ok", "1.5"}, {"global_localization", "ok", "12.0"}},
///                   {false, false, true});
std::string aligned_columns(const std::vector<std::vector<std::string>>& rows,
                            const std::vector<bool>& right = {}, const std::string& indent = "  ");

// ---- Numbers ----------------------------------------------------------------------------------

/// "12.3" with `digits` decimals; "–" when the value is missing, null or not a number.
std::string number(const nlohmann::json& value, int digits);
/// "mean ± sd (SE se, med m)" from the keys prefix_mean, prefix_std, prefix_median of an
/// experiment result; SE = sd/√n with n its "runs" (or "datasets"). Parts whose keys are
/// missing are left out.
std::string spread(const nlohmann::json& result, const std::string& prefix, int digits);
/// sd/√n; NaN when sd is not a finite number ≥ 0 or n < 2 (one run has no standard error).
double standard_error(const nlohmann::json& sd, const nlohmann::json& n);
/// A standard error with two significant digits ("0.0022", "0.13", "1.5", "150"), so that a
/// small SE next to a mean with fewer decimals does not print as 0; "–" when not finite or < 0.
std::string format_se(double se);

// ---- Agreement --------------------------------------------------------------------------------

/// A mean and its standard error (NaN when unknown; 0 for an exact value).
struct Estimate {
  double mean = std::numeric_limits<double>::quiet_NaN();
  double se = std::numeric_limits<double>::quiet_NaN();
};

/// How many combined standard errors two estimates of the same quantity may differ by and still
/// agree. 4.5 keeps false alarms rare over the report's few dozen comparisons (a two-sided
/// normal tail of 7e-6 each) while a real difference of a few SE over many runs still shows.
inline constexpr double kAgreementSigmas = 4.5;

/// "✓" when |ours − reference| ≤ kAgreementSigmas √(se_ours² + se_ref²), "✗" otherwise, "–"
/// when it cannot be computed (a mean or an SE unknown, or both SE 0).
std::string agreement(const Estimate& ours, const Estimate& reference);

// ---- Reference numbers ------------------------------------------------------------------------

/// The paper's Tables 2, 4, 5, 6 (and the numbers its text quotes), transcribed, and the
/// independent reference values of the corrected specification. They are data files,
/// <share>/data/report/paper.json and reference.json (data/report/README.md says where every
/// number comes from), stored in results.json under "paper" and "reference" so that the report
/// and the figure scripts draw them from there. Throw InvalidArgument (file missing) or
/// ParseError (not JSON, or a required key missing) naming the file.
nlohmann::json paper_numbers();
nlohmann::json reference_numbers();
/// Reads one numbers file: a JSON object with a "source" string and every key of `required`.
nlohmann::json read_numbers_file(const std::filesystem::path& file,
                                 const std::vector<std::string>& required);

// ---- Text -------------------------------------------------------------------------------------

/// The report's prose, <share>/data/report/text.json: a JSON object from a key to a string, or to
/// an array of strings joined with one space (data/report/README.md). Copies share the record of
/// the keys looked up, so a test can check that the file and the code use the same keys.
class Text {
 public:
  Text() = default;
  /// `strings` as read from `file`, which the errors name.
  Text(nlohmann::json strings, std::filesystem::path file);

  /// The text of `key`; ParseError naming the key and the file when it is missing.
  std::string operator()(const std::string& key) const;
  /// The text of `key` with its named placeholders filled: format("k", fmt::arg("runs", 500)).
  /// ParseError naming the key when fmt cannot format it.
  template <typename... Args>
  std::string format(const std::string& key, const Args&... args) const {
    const std::string pattern = (*this)(key);
    try {
      return fmt::format(fmt::runtime(pattern), args...);
    } catch (const fmt::format_error& e) {
      bad_placeholder(key, e.what());
    }
  }
  /// The texts of key.1, key.2, ... up to the first missing one (key.1 must exist): a list.
  std::vector<std::string> items(const std::string& key) const;

  /// Every key of the file.
  std::vector<std::string> keys() const;
  /// The keys looked up so far through this text or a copy of it.
  std::set<std::string> used() const { return used_ ? *used_ : std::set<std::string>(); }

 private:
  [[noreturn]] void bad_placeholder(const std::string& key, const std::string& what) const;

  std::shared_ptr<const nlohmann::json> strings_;
  std::filesystem::path file_;
  std::shared_ptr<std::set<std::string>> used_;
};

/// Reads a text file: a JSON object whose values are strings or arrays of strings. Throws
/// InvalidArgument (file missing) or ParseError (not JSON, or another value) naming the file.
Text read_text_file(const std::filesystem::path& file);
/// The bundled <share>/data/report/text.json.
Text report_text();

// ---- The report -------------------------------------------------------------------------------

/// Builds the whole report from results.json's content. `dir` is the output folder (to embed
/// CSV tables written by the experiments, e.g. table4_himmelblau.csv, when present).
Document build_report(const nlohmann::json& results, const std::filesystem::path& dir);

/// Writes the side-by-side tables as CSV (table2_slit.csv, table5_mcl.csv, table6_slam.csv)
/// into `dir`; returns the file names written. Rows exist only for configurations that ran.
/// A setting or result of the wrong type (a string where a number belongs) is refused with a
/// ParseError naming `source` (where `results` came from) and the key path.
std::vector<std::string> write_table_csvs(const nlohmann::json& results,
                                          const std::filesystem::path& dir,
                                          const std::filesystem::path& source = "results.json");

/// Reads a small CSV file (comma-separated, no quoting) into a table; throws ParseError naming
/// the file and line when a row has the wrong number of fields.
Table read_csv_table(const std::filesystem::path& file);

/// The configurations of one experiment in results.json ("runs" array), possibly empty.
const nlohmann::json& experiment_runs(const nlohmann::json& results, const std::string& name);

}  // namespace implicit::app::report
