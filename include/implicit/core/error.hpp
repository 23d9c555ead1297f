#pragma once
// Error policy (three tiers):
//  * bad user input (wrong sizes, NaN parameters, non-SPD covariances, malformed files) throws
//    implicit::InvalidArgument with an "expected X, got Y" message naming what and where;
//  * algorithm outcomes (Newton did not converge, weights degenerate) are reported in a status
//    or summary struct and never thrown from inside a per-particle loop;
//  * broken internal invariants are programming errors (assert).

#include <fmt/format.h>

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace implicit {

/// Thrown for invalid input supplied by the user of the library.
class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Thrown when an input file is malformed; the message names the file, line and field.
class ParseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws InvalidArgument with a formatted message when `condition` is false.
template <typename... Args>
inline void require(bool condition, fmt::format_string<Args...> format, Args&&... args) {
  if (!condition) throw InvalidArgument(fmt::format(format, std::forward<Args>(args)...));
}

/// Text from a data file made safe to quote in an error message: control bytes (ESC, NUL, ...)
/// and bytes >= 0x7f become `\xNN`, so a message cannot move a terminal's cursor or hide text;
/// anything past max_chars is cut and marked with "...".
inline std::string printable(std::string_view text, std::size_t max_chars = 80) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (out.size() >= max_chars) {
      out += "...";
      break;
    }
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f)
      out += static_cast<char>(c);
    else
      out += fmt::format("\\x{:02x}", c);
  }
  return out;
}

}  // namespace implicit
