#pragma once
// Where the installed read-only files live: the bundled data and the plot scripts.
//
//   auto data = implicit::find_share_dir("data", "IMPLICIT_DATA_DIR");   //
//   <prefix>/share/implicit/data
//
// Search order: the environment variable when it is set, else <folder of the running
// executable>/../share/implicit/<name>. `cmake --install` lays files out that way, and the build
// tree mirrors it (build/share/implicit/<name> links to the source folders), so programs find
// their files both installed and built, and no source path is compiled into the library.
// A program in another layout (an executable copied elsewhere, an embedding interpreter) sets the
// environment variable.

#include <filesystem>
#include <string_view>

namespace implicit {

/// Folder of the running executable (from /proc/self/exe); empty when it cannot be read.
std::filesystem::path executable_dir();

/// The folder `name` of the installed share tree, looked up as above. Throws InvalidArgument
/// naming every place it looked and how to point at the folder (the variable `env_var`, and
/// `hint`, e.g. a command-line flag) when none of them is an existing folder.
std::filesystem::path find_share_dir(std::string_view name, const char* env_var,
                                     std::string_view hint = {});

}  // namespace implicit
