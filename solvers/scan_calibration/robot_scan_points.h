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

// When the two-stage route cannot calibrate the bag (`why`: e.g. a featureless corridor, whose
// matches are degenerate, a gap each, leaving too few intervals), the scan points still constrain
// what the walls show in every pair: the refinement starts from the nominal wheels and tf's
// mounting (zero without tf) at the scans' stamps, and its result stands alone. `log` is the
// bag's matched log. Fails, saying why and what would help, without nominal wheels.
StatusOr<RobotBagCalibration> CalibrateOnScanPointsAlone(const RobotMessages& bag,
                                                         const RobotBagOptions& options,
                                                         RobotBagLog log, const Status& why);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_CALIBRATION_ROBOT_SCAN_POINTS_H_
