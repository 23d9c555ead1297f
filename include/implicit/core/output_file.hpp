#pragma once
// Output files written whole or not at all: under a temporary name in the same folder, renamed
// over the final name once every byte was written (a rename within one folder is atomic). A
// killed process or a full disk leaves the previous file (or none), never a half-written one
// under the final name. The one writer of the library (write_text_file, save_map) and of the
// command line (apps/, experiments/).

#include <filesystem>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/ostream.h>

namespace implicit {

/// An output file written under a temporary name beside `path` (`path`.tmp<pid>) and renamed over
/// it by commit(), which first checks that every write succeeded. Without commit() (an exception,
/// an early return) the temporary file is removed. A name ending in ".gz" is gzip-compressed.
///   OutputFile out(ctx.csv_path("runs.csv"));
///   out.print("{},{}\n", a, b);
///   out.commit();  // throws InvalidArgument "--out: DIR/runs.csv: expected a writable output
///                  // file, got ..." when the file could not be written or renamed
class OutputFile {
 public:
  enum class Mode {
    kReplace,  ///< the new content replaces the file
    kAppend,   ///< the existing content, then what is written (the *_summary.csv files)
    kRecord,   ///< like kReplace, for a file the program keeps for itself (a --resume record):
               ///< not counted by completed_outputs()
  };
  /// `flag`: the option (or function) that chose where the file goes, named first in the error;
  /// empty: the error starts with the file.
  explicit OutputFile(std::filesystem::path path, Mode mode = Mode::kReplace,
                      std::string flag = "--out");
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  std::ostream& stream();
  /// Formatted text, as fmt::print (the CSV writers use it).
  template <typename... T>
  void print(fmt::format_string<T...> format, T&&... args) {
    fmt::print(stream(), format, std::forward<T>(args)...);
  }
  /// True when the file did not exist before (to write a CSV header once in append mode).
  bool fresh() const { return fresh_; }
  const std::filesystem::path& path() const { return path_; }
  void commit();

 private:
  [[noreturn]] void fail(const std::string& what);
  std::filesystem::path path_, temporary_;
  std::string flag_;
  std::unique_ptr<std::ostream> out_;
  std::string open_error_;  ///< why the temporary file could not be created (empty: it was)
  Mode mode_;
  bool gzip_ = false;
  bool fresh_ = true;
  bool committed_ = false;
  int slot_ = -1;  ///< where remove_unfinished_outputs() finds the temporary name
};

/// The whole of `text` into `path` through an OutputFile (gzip when the name ends in ".gz").
void write_output_file(const std::filesystem::path& path, std::string_view text,
                       const std::string& flag = "--out");

/// A file another process (a plot script) writes on this program's behalf: while this object
/// lives, remove_unfinished_outputs() removes it, since a stopped writer leaves it half-written.
class UnfinishedOutput {
 public:
  explicit UnfinishedOutput(const std::filesystem::path& path);
  ~UnfinishedOutput();
  UnfinishedOutput(const UnfinishedOutput&) = delete;
  UnfinishedOutput& operator=(const UnfinishedOutput&) = delete;

 private:
  int slot_ = -1;
};

/// For a SIGINT/SIGTERM handler (async-signal-safe): removes the temporary files of the outputs
/// not committed yet and the UnfinishedOutput files; returns how many were removed.
int remove_unfinished_outputs() noexcept;

/// How many outputs were committed in this process (Mode::kRecord not counted); async-signal-safe.
int completed_outputs() noexcept;

/// The final paths of the outputs committed in this process, in commit order (Mode::kRecord not
/// included): `implicit reproduce` lists its run's files in results.json with them.
std::vector<std::filesystem::path> committed_output_paths();

}  // namespace implicit
