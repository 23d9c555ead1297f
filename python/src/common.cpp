// Argument checks shared by the bindings: shapes and finiteness (messages naming both shapes),
// numbers, integers, seeds, flags, choices and paths (messages naming the argument and the range).
#include "common.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace implicit::python {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) s += (k ? ", " : "") + std::to_string(a.shape(k));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

Array require_shape(const py::handle& object, const std::string& name,
                    std::vector<py::ssize_t> shape, bool finite) {
  Array a;
  try {
    a = Array::ensure(object);
  } catch (const py::error_already_set&) {
  }
  require(static_cast<bool>(a), "{}: expected an array of numbers, got {}", name,
          std::string(py::str(py::type::handle_of(object).attr("__name__"))));
  bool ok = a.ndim() == static_cast<py::ssize_t>(shape.size());
  for (std::size_t k = 0; ok && k < shape.size(); ++k)
    ok = shape[k] < 0 || a.shape(static_cast<py::ssize_t>(k)) == shape[k];
  if (!ok) {
    std::string want = "(";
    for (std::size_t k = 0; k < shape.size(); ++k)
      want += (k ? ", " : "") + (shape[k] < 0 ? std::string("n") : std::to_string(shape[k]));
    want += shape.size() == 1 ? ",)" : ")";
    throw InvalidArgument(
        fmt::format("{}: expected shape {}, got shape {}", name, want, shape_text(a)));
  }
  if (finite) {
    for (py::ssize_t k = 0; k < a.size(); ++k)
      require(std::isfinite(a.data()[k]), "{}: expected finite values, got {} at flat index {}",
              name, a.data()[k], k);
  }
  return a;
}

namespace {

constexpr double kArgInf = std::numeric_limits<double>::infinity();

std::string arg_bounds_text(double lo, double hi, bool lo_open) {
  if (lo == -kArgInf && hi == kArgInf) return "a finite number";
  if (hi == kArgInf) return fmt::format("a finite number {} {}", lo_open ? ">" : ">=", lo);
  if (lo == -kArgInf) return fmt::format("a number <= {}", hi);
  return fmt::format("a number in {}{}, {}]", lo_open ? "(" : "[", lo, hi);
}

std::string arg_choices_text(const std::vector<std::string>& allowed) {
  std::string s;
  for (std::size_t k = 0; k < allowed.size(); ++k)
    s += fmt::format("{}'{}'", k == 0 ? "" : (k + 1 == allowed.size() ? " or " : ", "), allowed[k]);
  return s;
}

/// The Python int of an integer-like object (int, numpy integer; not bool, float or str), or a
/// null object.
py::object arg_as_int(const py::handle& o) {
  if (py::isinstance<py::bool_>(o)) return {};
  try {
    return py::module_::import("operator").attr("index")(o);
  } catch (const py::error_already_set&) {
    return {};
  }
}

}  // namespace

std::string type_name(const py::handle& o) {
  return py::str(py::type::handle_of(o).attr("__name__"));
}

double number_arg(const py::handle& o, const std::string& name, double lo, double hi,
                  bool lo_open) {
  double v = 0.0;
  // Strings are refused (pybind11 would not parse them either); numpy scalars are numbers.
  bool ok = !py::isinstance<py::str>(o) && !o.is_none();
  if (ok) {
    try {
      v = o.cast<double>();
    } catch (const py::cast_error&) {
      ok = false;
    } catch (const py::error_already_set&) {
      ok = false;
    }
  }
  require(ok, "{}: expected {}, got {}", name, arg_bounds_text(lo, hi, lo_open), type_name(o));
  require(std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi, "{}: expected {}, got {}",
          name, arg_bounds_text(lo, hi, lo_open), v);
  return v;
}

long long int_arg(const py::handle& o, const std::string& name, long long lo, long long hi) {
  const std::string want = hi == std::numeric_limits<long long>::max()
                               ? fmt::format("an integer >= {}", lo)
                               : fmt::format("an integer in [{}, {}]", lo, hi);
  const py::object i = arg_as_int(o);
  require(static_cast<bool>(i), "{}: expected {}, got {}", name, want, type_name(o));
  long long v = 0;
  try {
    v = i.cast<long long>();
  } catch (const py::cast_error&) {  // beyond 64 bits: out of range whatever the bounds
    throw InvalidArgument(
        fmt::format("{}: expected {}, got {}", name, want, std::string(py::str(i))));
  }
  require(v >= lo && v <= hi, "{}: expected {}, got {}", name, want, v);
  return v;
}

std::uint64_t seed_arg(const py::handle& o, const std::string& name) {
  const char* want = "an integer in [0, 2^64 - 1]";
  const py::object i = arg_as_int(o);
  require(static_cast<bool>(i), "{}: expected {}, got {}", name, want, type_name(o));
  // Compared in Python: the C++ cast would wrap -1 to 2^64 - 1 without a word.
  const py::int_ zero(0);
  const py::object limit = py::int_(1).attr("__lshift__")(64);
  require(i.attr("__ge__")(zero).cast<bool>() && i.attr("__lt__")(limit).cast<bool>(),
          "{}: expected {}, got {}", name, want, std::string(py::str(i)));
  return i.cast<std::uint64_t>();
}

std::size_t particle_count_arg(const py::handle& o, const std::string& name, long long hi,
                               double bytes_each) {
  if (const py::object i = arg_as_int(o)) {
    long long v = 0;
    bool fits = true;
    try {
      v = i.cast<long long>();
    } catch (const py::cast_error&) {  // beyond 64 bits: int_arg's message
      fits = false;
    }
    if (fits && v > hi) {
      const double bytes = static_cast<double>(v) * bytes_each;
      const bool gib = bytes >= double(1 << 30);
      throw InvalidArgument(fmt::format(
          "{}: expected an integer in [1, {}], got {}: {} particles would take at least {:.3g} "
          "{} ({} bytes each)",
          name, hi, v, v, bytes / (gib ? double(1 << 30) : double(1 << 20)), gib ? "GiB" : "MiB",
          bytes_each));
    }
  }
  return static_cast<std::size_t>(int_arg(o, name, 1, hi));
}

bool bool_arg(const py::handle& o, const std::string& name) {
  require(py::isinstance<py::bool_>(o), "{}: expected True or False, got {}", name, type_name(o));
  return o.cast<bool>();
}

std::string choice_arg(const py::handle& o, const std::string& name,
                       const std::vector<std::string>& allowed) {
  const std::string text = arg_choices_text(allowed);
  require(py::isinstance<py::str>(o), "{}: expected {}, got {}", name, text, type_name(o));
  const std::string s = o.cast<std::string>();
  for (const std::string& a : allowed)
    if (s == a) return s;
  throw InvalidArgument(fmt::format("{}: expected {}, got '{}'", name, text, printable(s)));
}

std::string choice_arg(const py::handle& o, const std::string& name,
                       std::initializer_list<const char*> allowed) {
  return choice_arg(o, name, std::vector<std::string>(allowed.begin(), allowed.end()));
}

std::filesystem::path path_arg(const py::handle& o, const std::string& name) {
  py::object p;
  try {
    p = py::module_::import("os").attr("fspath")(o);
  } catch (const py::error_already_set&) {
  }
  require(p && py::isinstance<py::str>(p), "{}: expected a path (str or os.PathLike), got {}", name,
          type_name(o));
  const std::string s = p.cast<std::string>();
  require(!s.empty(), "{}: expected a file name, got an empty string", name);
  return s;
}

}  // namespace implicit::python
