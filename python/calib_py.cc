// The Python module `calib`: reading, calibration and diagnosis of laser and bearing logs through
// the library (the same calls as the command line), results as dicts of NumPy arrays.
#include <glog/logging.h>

#include "py_util.h"

PYBIND11_MODULE(calib, m) {
  m.doc() =
      "Calibration of a differential-drive robot from its logs (laser-odometry, Censi et al.; "
      "bearing-only, Martinelli). Failures raise OSError (a file that cannot be read), "
      "ValueError (input the library refuses) or RuntimeError, with the library's message.";
  // Ceres warns through glog when a covariance is rank deficient; the results say why themselves.
  FLAGS_minloglevel = std::max(FLAGS_minloglevel, 2);
  calib::python::BindLaser(m);
  calib::python::BindBearing(m);
}
