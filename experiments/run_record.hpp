#pragma once
// The result of one run of an experiment as a named record: a struct with named fields and one
// field table (name + member pointer) from which everything else is derived, so that no number
// of a run is ever read by its position.
//
//   struct SlitRunRecord {
//     double error_x = 0.0;
//     bool crashed = false;
//     static constexpr auto fields() {
//       using F = RecordField<SlitRunRecord>;
//       return std::array{F{"error_x", &SlitRunRecord::error_x},
//                         F{"crashed", &SlitRunRecord::crashed}};
//     }
//   };
//
// From the table: the numbers that cross between ranks and go into the --resume files
// (record_values / record_from_values, in the table's order), and the JSON by name
// (record_json). A record file that `--resume` keeps in <out>/.resume/
// (experiments/parallel_runs.hpp) is the run's key, the count, then one number per line in
// hexadecimal floating point (exact, NaN and inf too). The file format is separate from
// parallel_runs.cpp so that the fuzz target reads records alone.

#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace implicit::experiments {

/// A record's numbers as they travel: the fields in table order; a text field or a list is its
/// length followed by its entries (characters as their codes). Only record_values and
/// record_from_values read or write it.
using RecordValues = std::vector<double>;

/// One named field of the record type R.
template <typename R>
struct RecordField {
  using Member = std::variant<double R::*, bool R::*, int R::*, std::size_t R::*, std::string R::*,
                              std::vector<double> R::*>;
  std::string_view name;
  Member member;
};

/// A record type: a struct with a static fields() returning its table (an array of RecordField).
template <typename R>
concept NamedRecord = requires {
  { R::fields()[0] } -> std::convertible_to<RecordField<R>>;
};

/// The numbers of `r`, field by field in table order.
template <NamedRecord R>
RecordValues record_values(const R& r) {
  RecordValues out;
  for (const RecordField<R>& f : R::fields())
    std::visit(
        [&](auto member) {
          using T = std::remove_cvref_t<decltype(r.*member)>;
          const T& v = r.*member;
          if constexpr (std::is_same_v<T, std::string> || std::is_same_v<T, std::vector<double>>) {
            out.push_back(static_cast<double>(v.size()));
            for (const auto x : v) out.push_back(static_cast<double>(x));
          } else if constexpr (std::is_same_v<T, bool>) {
            out.push_back(v ? 1.0 : 0.0);
          } else {
            out.push_back(static_cast<double>(v));
          }
        },
        f.member);
  return out;
}

/// Reads `values` (record_values of an R) into `r`. Returns why they are not one ("expected a
/// length for field 'name' at number 21, got 2.5", ...), empty when they are; never throws.
template <NamedRecord R>
std::string record_from_values(const RecordValues& values, R& r) {
  std::size_t at = 0;
  std::string why;
  // A length or an integer field: a whole number in [0, limit] (an int: of either sign).
  const auto whole = [](double x, double lo, double hi) {
    return std::isfinite(x) && x == std::floor(x) && x >= lo && x <= hi;
  };
  for (const RecordField<R>& f : R::fields()) {
    if (at >= values.size())
      return fmt::format("expected field '{}' at number {}, got the end", f.name, at + 1);
    std::visit(
        [&](auto member) {
          using T = std::remove_cvref_t<decltype(r.*member)>;
          T& v = r.*member;
          const double x = values[at++];
          if constexpr (std::is_same_v<T, std::string> || std::is_same_v<T, std::vector<double>>) {
            const auto left = static_cast<double>(values.size() - at);
            if (!whole(x, 0.0, left)) {
              why = fmt::format("expected a length in [0, {}] for field '{}' at number {}, got {}",
                                values.size() - at, f.name, at, x);
              return;
            }
            v.resize(static_cast<std::size_t>(x));
            for (auto& e : v) e = static_cast<typename T::value_type>(values[at++]);
          } else if constexpr (std::is_same_v<T, bool>) {
            v = x != 0.0;
          } else if constexpr (std::is_same_v<T, double>) {
            v = x;
          } else {
            const double lo = std::is_signed_v<T> ? -2147483648.0 : 0.0;
            const double hi = std::is_signed_v<T> ? 2147483647.0 : 9007199254740992.0;
            if (!whole(x, lo, hi)) {
              why = fmt::format("expected a whole number for field '{}' at number {}, got {}",
                                f.name, at, x);
              return;
            }
            v = static_cast<T>(x);
          }
        },
        f.member);
    if (!why.empty()) return why;
  }
  if (at != values.size())
    return fmt::format("expected {} numbers (the record's fields), got {}", at, values.size());
  return {};
}

/// The record by name: one key per field (NaN and inf as null, as nlohmann::json writes them).
template <NamedRecord R>
nlohmann::json record_json(const R& r) {
  nlohmann::json j = nlohmann::json::object();
  for (const RecordField<R>& f : R::fields())
    std::visit([&](auto member) { j[std::string(f.name)] = r.*member; }, f.member);
  return j;
}

/// The field of every record, in run order.
template <NamedRecord R, typename T>
std::vector<double> column(const std::vector<R>& records, T R::*field) {
  std::vector<double> c;
  c.reserve(records.size());
  for (const R& r : records) c.push_back(static_cast<double>(r.*field));
  return c;
}

/// The text of the record file of `values` under `key` (no newline inside the key).
std::string format_run_record(const std::string& key, const RecordValues& values);

/// Reads `text` as a record file of `key` into `values`. Returns why it is not one ("got an empty
/// file", "expected 6 numbers, got 'x' on line 3", ...), empty when it is; never throws for any
/// text. At most 2^20 numbers: a bound, so that an edited count cannot exhaust memory.
std::string parse_run_record(const std::string& text, const std::string& key, RecordValues& values);

}  // namespace implicit::experiments
