#ifndef CALIB_PYTHON_PY_UTIL_H_
#define CALIB_PYTHON_PY_UTIL_H_

#include <calib/core/status.h>
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

// What the binding files share: failures as Python exceptions, JSON reports as dicts.
namespace calib::python {

namespace py = pybind11;

// A C-contiguous float64 view of whatever the caller passed (lists, other dtypes are converted).
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Raises the Python exception for a failed `status`, with the library's message: OSError for a
// file that cannot be read or written, ValueError for input the library refuses (malformed, or
// not determining the parameters), RuntimeError otherwise (no convergence, internal errors).
[[noreturn]] void Raise(const Status& status);

inline void Check(const Status& status) {
  if (!status.ok()) Raise(status);
}

template <typename T>
T Unwrap(StatusOr<T> value) {
  if (!value.ok()) Raise(value.status());
  return std::move(value).value();
}

// The report's JSON as Python objects (dicts keep the report's key order).
py::object JsonToPython(const nlohmann::ordered_json& json);

void BindLaser(py::module_& m);
void BindBearing(py::module_& m);

}  // namespace calib::python

#endif  // CALIB_PYTHON_PY_UTIL_H_
