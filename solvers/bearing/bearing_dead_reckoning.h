#ifndef CALIB_SOLVERS_BEARING_BEARING_DEAD_RECKONING_H_
#define CALIB_SOLVERS_BEARING_BEARING_DEAD_RECKONING_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/se2.h>
#include <calib/solvers/bearing/calibrate_bearing.h>

#include <Eigen/Core>
#include <vector>

// What a person checks a bearing-only calibration with: each run's robot path as the bundle
// adjustment placed it (bearings and encoders together) against dead reckoning from the same start
// with the nominal wheels (δR = δL = δB = 1) and with the calibrated ones, and the motion covered.
// Poses are in the landmark's frame (landmark at the origin), in metres when the log gives an
// initial distance and otherwise in units of the right wheel's nominal travel (the gauge δR ≡ 1:
// the bearings do not fix the scale).
namespace calib {

struct BearingRunPaths {
  int run = 0;
  size_t index = 0;          // In the log's runs and the result's per-run vectors.
  std::vector<double> t_s;   // Node times (the run's start, then its bearings).
  std::vector<int> bearing;  // Per node, its bearing's index in the run (−1: the start node).
  std::vector<Pose2d> adjusted, nominal, calibrated;
  // Robot speeds under the calibration from the previous node to this one (0 at the first).
  std::vector<double> v_mps, omega_radps;
};

struct BearingPaths {
  bool metric = false;                // Lengths in metres (an initial distance was given).
  std::vector<BearingRunPaths> runs;  // Runs whose nodes match the result's poses.
};

BearingPaths BearingDeadReckoning(const BearingLog& log, const BearingCalibrationResult& result);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_DEAD_RECKONING_H_
