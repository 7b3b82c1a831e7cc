#ifndef CALIB_SOLVERS_LASER_LASER_OBSERVABILITY_H_
#define CALIB_SOLVERS_LASER_LASER_OBSERVABILITY_H_

#include <calib/core/laser/laser_params.h>
#include <calib/solvers/laser/laser_motion.h>

#include <string>
#include <vector>

namespace calib {

// How well the log determines each parameter and which combination it determines worst. The
// covariance is scaled to relative units first (radii and b by their values, the sensor offset
// by b, the angle in radians) so that directions of mixed units compare fairly.
struct LaserObservability {
  LaserParamVector relative_sigma;      // σ in the scaled units.
  LaserParamVector weakest_direction;   // Unit vector in the scaled units.
  double weakest_relative_sigma = 0.0;  // σ along the weakest direction.
  double condition_number = 0.0;        // Of the scaled information matrix.
  std::string weakest_description;      // The weakest direction in words.
  std::vector<std::string> warnings;    // Plain-words problems (empty when all is well).
};

LaserObservability AnalyzeLaserObservability(const LaserParamMatrix& covariance,
                                             const LaserCalibration& estimate,
                                             const LaserMotionCensus& census);

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_OBSERVABILITY_H_
