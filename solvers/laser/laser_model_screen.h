#ifndef CALIB_SOLVERS_LASER_LASER_MODEL_SCREEN_H_
#define CALIB_SOLVERS_LASER_LASER_MODEL_SCREEN_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/status.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <string>
#include <vector>

// calibrate's quick look for physics the base model leaves out, so that its verdict can point to
// `calib diagnose`: the diagnosis' first step only (the score test of every candidate at the base
// fit, Holm at the family-wise level, and the residual-structure tests), nothing adopted. It
// costs about one more calibration.
namespace calib {

struct LaserModelScreen {
  bool flagged = false;
  std::vector<std::string> effects;  // Candidates whose score test rejects the base model.
  std::string structure;             // The residual-structure sentence when it found structure.
  std::string warning;               // One sentence for the result's warnings (empty: nothing).
};

// `sample_times_estimated`: the intervals lie between estimated sample times (raw streams).
StatusOr<LaserModelScreen> ScreenLaserModel(const std::vector<LaserInterval>& intervals,
                                            const LaserCalibrationOptions& calibration,
                                            bool sample_times_estimated = false);

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_MODEL_SCREEN_H_
