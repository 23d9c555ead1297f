#include "implicit/core/share_dir.hpp"

#include <cstdlib>
#include <string>
#include <system_error>

#include <fmt/format.h>

#include "implicit/core/error.hpp"

namespace implicit {

std::filesystem::path executable_dir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : exe.parent_path();
}

std::filesystem::path find_share_dir(std::string_view name, const char* env_var,
                                     std::string_view hint) {
  std::error_code ec;
  if (const char* env = std::getenv(env_var); env != nullptr && *env != '\0') {
    // An explicit choice is never overridden by the install layout: a wrong value is an error.
    if (std::filesystem::is_directory(env, ec)) return env;
    throw InvalidArgument(fmt::format("{}={}: expected an existing folder, got none{}", env_var,
                                      env, hint.empty() ? "" : fmt::format(" ({})", hint)));
  }
  const auto exe_dir = executable_dir();
  const auto beside =
      exe_dir.empty() ? std::filesystem::path()
                      : (exe_dir.parent_path() / "share" / "implicit" / name).lexically_normal();
  if (!beside.empty() && std::filesystem::is_directory(beside, ec)) return beside;
  throw InvalidArgument(fmt::format(
      "no {} folder found: looked in ${} (unset) and {} (missing); set {} to the folder "
      "that holds the {} files{}",
      name, env_var,
      beside.empty() ? "<executable>/../share/implicit/" + std::string(name) : beside.string(),
      env_var, name, hint.empty() ? "" : fmt::format(", or {}", hint)));
}

}  // namespace implicit
