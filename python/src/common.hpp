#pragma once
// Shared helpers of the Python extension: numpy arrays that own C++ buffers without copying
// them, and the argument checks that turn bad shapes, types and values into InvalidArgument
// (ValueError) naming the argument. pybind11's own conversions would raise a TypeError listing
// the whole signature, or a RuntimeError ("Unable to cast"), instead of the argument at fault.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "implicit/core/error.hpp"

namespace implicit::python {

namespace py = pybind11;

/// A numpy array over the buffer of `owner`, which is moved to the heap and freed with the array:
/// large results (samples, weights) reach Python without a copy.
/// Owner: std::vector<double> or a dynamic Eigen matrix (heap storage, data() after the move).
template <typename Owner>
py::array_t<double> adopt(Owner&& owner, std::vector<py::ssize_t> shape) {
  auto* kept = new Owner(std::move(owner));
  const double* p = kept->data();
  py::capsule free_it(kept, [](void* o) { delete static_cast<Owner*>(o); });
  std::vector<py::ssize_t> strides(shape.size());
  py::ssize_t step = sizeof(double);
  for (std::size_t k = shape.size(); k-- > 0;) {
    strides[k] = step;
    step *= shape[k];
  }
  return py::array_t<double>(shape, strides, p, free_it);
}

inline py::array_t<double> adopt_vector(std::vector<double>&& v) {
  const auto n = static_cast<py::ssize_t>(v.size());
  return adopt(std::move(v), {n});
}

/// A read-only float64 array of the given shape; -1 in `shape` accepts any length. The message
/// names the argument and both shapes.
using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
Array require_shape(const py::handle& object, const std::string& name,
                    std::vector<py::ssize_t> shape, bool finite = true);

std::string shape_text(const py::array& a);

/// The name of a Python object's type, for messages ("got str").
std::string type_name(const py::handle& o);

/// No bound, for number_arg (lo = -kUnbounded, hi = kUnbounded).
inline constexpr double kUnbounded = std::numeric_limits<double>::infinity();

/// A Python number as a double in [lo, hi] (lo excluded when lo_open); NaN and infinities are
/// refused. The message names `name` and the bounds.
double number_arg(const py::handle& o, const std::string& name, double lo, double hi,
                  bool lo_open = false);
/// A Python integer (not a float: 2.5 particles is a mistake, not 2) in [lo, hi].
long long int_arg(const py::handle& o, const std::string& name, long long lo, long long hi);
/// A seed: an integer in [0, 2^64 - 1], the range of the tool's --seed.
std::uint64_t seed_arg(const py::handle& o, const std::string& name);

/// The most particles the tool takes (--particles of `implicit mcl`, with or without
/// --sensor laser): the one-call runners, implicit.ssm and the filters stepped from Python refuse
/// more, as the tool does (tests/test_runs_bad_input.py compares it with `implicit mcl --help`).
inline constexpr long long kMaxParticles = 10'000'000;
/// The most of `implicit slam --particles`, which carry a map each.
inline constexpr long long kMaxSlamParticles = 1'000'000;
/// Bytes per particle of a pose filter: the pose and its copy for resampling, the weight and
/// the log weight (ParticleEngine); what a count costs at least.
inline constexpr double kPoseParticleBytes = (2 * 3 + 2) * sizeof(double);
/// A particle count, an integer in [1, hi]; a larger one is refused with the memory it would
/// take at `bytes_each` bytes per particle (a lower bound: the state and its weights).
std::size_t particle_count_arg(const py::handle& o, const std::string& name, long long hi,
                               double bytes_each);
/// True or False (not any object with a truth value).
bool bool_arg(const py::handle& o, const std::string& name);
/// A str that is one of `allowed`.
std::string choice_arg(const py::handle& o, const std::string& name,
                       std::initializer_list<const char*> allowed);
/// The same for a list of names drawn from a registry (experiments/choices.hpp's ChoiceSet).
std::string choice_arg(const py::handle& o, const std::string& name,
                       const std::vector<std::string>& allowed);
/// A str or os.PathLike naming a file.
std::filesystem::path path_arg(const py::handle& o, const std::string& name);

}  // namespace implicit::python
