#include "py_util.h"

#include <stdexcept>

namespace calib::python {

void Raise(const Status& status) {
  switch (status.code()) {
    case StatusCode::kIo:
      PyErr_SetString(PyExc_OSError, status.message().c_str());
      throw py::error_already_set();
    case StatusCode::kInvalidInput:
    case StatusCode::kNotObservable:
      throw py::value_error(status.message());
    default:
      throw std::runtime_error(status.message());
  }
}

py::object JsonToPython(const nlohmann::ordered_json& json) {
  // NaN and infinities are written as null, as in the report files.
  return py::module_::import("json").attr("loads")(json.dump());
}

}  // namespace calib::python
