#pragma once
// Runs the `implicit` command line (path from the IMPLICIT_CLI compile definition) or any shell
// command, capturing exit code, stdout and stderr; and a temporary folder removed on success.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace implicit::test {

struct CommandResult {
  int code = -1;
  std::string out;
  std::string err;
};

inline std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Writes `text` to `file`, creating its folder.
inline void write_file(const std::filesystem::path& file, const std::string& text) {
  std::filesystem::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

/// A fresh folder under the system temp dir; removed when the test passed, kept otherwise.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("implicit_test_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    if (!::testing::Test::HasFailure()) std::filesystem::remove_all(path_);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

inline CommandResult run_shell(const std::string& command) {
  static int counter = 0;
  const auto base =
      std::filesystem::temp_directory_path() /
      ("implicit_cmd_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  const std::string out = base.string() + ".out", err = base.string() + ".err";
  const int raw = std::system((command + " > '" + out + "' 2> '" + err + "'").c_str());
  CommandResult r;
  r.code = raw == -1 ? -1 : (WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw));
  r.out = read_file(out);
  r.err = read_file(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

inline CommandResult run_cli(const std::string& args) {
  return run_shell(std::string("'") + IMPLICIT_CLI + "' " + args);
}

}  // namespace implicit::test
