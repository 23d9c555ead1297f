// Argument checks shared by the bindings: shapes and finiteness, with messages naming both shapes.
#include "common.hpp"

#include <cmath>

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

}  // namespace implicit::python
