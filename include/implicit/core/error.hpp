#pragma once
// Error policy (three tiers):
//  * bad user input (wrong sizes, NaN parameters, non-SPD covariances, malformed files) throws
//    implicit::InvalidArgument with an "expected X, got Y" message naming what and where;
//  * algorithm outcomes (Newton did not converge, weights degenerate) are reported in a status
//    or summary struct and never thrown from inside a per-particle loop;
//  * broken internal invariants are programming errors (assert).

#include <fmt/format.h>

#include <stdexcept>
#include <string>

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

}  // namespace implicit
