#ifndef CALIB_SOLVERS_SCAN_CALIBRATION_ROBOT_SCAN_POINTS_H_
#define CALIB_SOLVERS_SCAN_CALIBRATION_ROBOT_SCAN_POINTS_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/status.h>
#include <calib/solvers/scan_calibration/scan_point_calibration.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>

// A bag's two-stage calibration refined against its scan points: the distinct scans of the last
// pass (mirrored as they were matched), each at the time the timing calibration gave its sample
// (scans it did not time, e.g. failed matches, at their stamp plus the median correction), and
// the wheel angles the calibration read.
namespace calib {

StatusOr<ScanPointCalibration> RefineRobotOnScanPoints(const RobotMessages& bag,
                                                       const RobotBagCalibration& two_stage,
                                                       const ScanPointOptions& options);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_CALIBRATION_ROBOT_SCAN_POINTS_H_
