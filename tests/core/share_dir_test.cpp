// Where installed read-only files are found (core/share_dir.hpp): the environment variable wins,
// else ../share/implicit/<name> next to the running executable (the build tree mirrors the
// install layout), else an error that names every place looked and the variable to set.
// Each test runs in its own process (gtest_discover_tests), so changing the environment is safe.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "implicit/core/error.hpp"
#include "implicit/core/share_dir.hpp"

namespace implicit {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::string error_of(std::string_view name, const char* env_var) {
  try {
    find_share_dir(name, env_var, "--data DIR");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "no error";
}

TEST(ShareDir, ExecutableDirIsTheFolderOfThisTestProgram) {
  const auto dir = executable_dir();
  ASSERT_FALSE(dir.empty());
  EXPECT_TRUE(std::filesystem::is_directory(dir));
  EXPECT_TRUE(std::filesystem::exists(dir / "test_core"));
}

TEST(ShareDir, FindsTheDataNextToTheExecutable) {
  unsetenv("IMPLICIT_TEST_SHARE_DIR");
  const auto data = find_share_dir("data", "IMPLICIT_TEST_SHARE_DIR");
  EXPECT_EQ(data,
            (executable_dir().parent_path() / "share" / "implicit" / "data").lexically_normal());
  EXPECT_TRUE(std::filesystem::exists(data / "carpark" / "carpark_dr.csv"));
}

TEST(ShareDir, TheEnvironmentVariableWins) {
  const auto tmp = std::filesystem::temp_directory_path();
  setenv("IMPLICIT_TEST_SHARE_DIR", tmp.c_str(), 1);
  EXPECT_EQ(find_share_dir("data", "IMPLICIT_TEST_SHARE_DIR"), tmp);
}

TEST(ShareDir, AVariableNamingNoFolderIsAnError) {
  setenv("IMPLICIT_TEST_SHARE_DIR", "/no/such/folder", 1);
  EXPECT_THAT(error_of("data", "IMPLICIT_TEST_SHARE_DIR"),
              AllOf(HasSubstr("IMPLICIT_TEST_SHARE_DIR=/no/such/folder"),
                    HasSubstr("expected an existing folder"), HasSubstr("--data DIR")));
}

TEST(ShareDir, AMissingFolderNamesWhereItLookedAndHowToPointAtIt) {
  unsetenv("IMPLICIT_TEST_SHARE_DIR");
  const std::string expected_place =
      (executable_dir().parent_path() / "share" / "implicit" / "no-such-name").string();
  EXPECT_THAT(error_of("no-such-name", "IMPLICIT_TEST_SHARE_DIR"),
              AllOf(HasSubstr("no no-such-name folder found"),
                    HasSubstr("$IMPLICIT_TEST_SHARE_DIR (unset)"), HasSubstr(expected_place),
                    HasSubstr("set IMPLICIT_TEST_SHARE_DIR"), HasSubstr("--data DIR")));
}

}  // namespace
}  // namespace implicit
