#ifndef CALIB_SOLVERS_SCAN_MATCHING_ROBOT_BAG_LOG_H_
#define CALIB_SOLVERS_SCAN_MATCHING_ROBOT_BAG_LOG_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/bag/robot_topics.h>
#include <calib/core/bag/tf_tree.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/status.h>
#include <calib/solvers/scan_calibration/scan_point_calibration.h>
#include <calib/solvers/scan_matching/beam_timing.h>
#include <calib/solvers/scan_matching/scan_laser_log.h>
#include <calib/solvers/scan_matching/wall_check.h>
#include <calib/solvers/timing/laser_timing_calibration.h>

#include <optional>
#include <string>
#include <vector>

// A robot's recording (a bag's messages) to the laser calibration's stream log: the topics
// picked, the wheel angles from the joint states (or the driver's odometry through the nominal
// radius and wheelbase), the nominal mounting from tf, and the scans matched into sensor poses.
namespace calib {

struct RobotBagOptions {
  TopicChoice topics;
  // The nominal values the robot's driver uses: needed when the wheel angles come from Odometry
  // (the calibration then returns corrections to them); otherwise they only seed the matcher.
  double nominal_wheel_radius_m = 0.0;
  double nominal_wheelbase_m = 0.0;
  // The JointState positions' unit in radians: π/180 for degrees, 2π/N for raw encoder counts of
  // N per wheel turn.
  double wheel_radians_per_unit = 1.0;
  std::string base_frame;  // Empty: base_link, else base_footprint, else Odometry's child frame.
  double sensor_time_offset_s = 0.0;  // A known latency: a scan stamped t began at t + this.
  ScanOdometryOptions matching;
  // A calibration of this robot (a first pass): the matcher's guesses and the de-skewing of each
  // sweep then go through it instead of the nominal values.
  std::optional<LaserCalibration> calibrated;
  // With `calibrated`: its estimate of when the scans were taken (the wheels' clock; per scan of
  // the scan topic, ScanSweepStarts), where the de-skewing follows the sensor (a stamp at the
  // sweep's end, not its start; a pick-up stamp up to a period after its sample).
  SweepStarts calibrated_sweep_starts;
  // When set, the calibration is refined against the scan points after the two-stage route; and
  // where that route cannot calibrate (too few matches), the scan points calibrate alone from
  // the nominal wheels (CalibrateOnScanPointsAlone).
  std::optional<ScanPointOptions> scan_points;
  bool keep_unmatched = false;  // ScanLogOptions::keep_unmatched, for the scan points alone.
  // With `calibrated` set: check the beams' timing against the data (beam_timing.h) unless
  // `beam_timing` already holds a check, whose timing then applies to every scan.
  bool check_beam_timing = true;
  std::optional<BeamTimingCheck> beam_timing;
  // Beams that return from the robot's own body (self_returns.h) are left out of every scan.
  bool mask_self_returns = true;
};

struct RobotBagLog {
  ScanLog scans;  // scans.log: the stream log the calibration reads.
  PickedTopics topics;
  bool wheels_from_odometry = false;
  std::string wheel_source;  // For the summary: "/joint_states (left_wheel_joint, ...)".
  std::string base_frame, sensor_frame;
  std::optional<PlanarMounting> nominal_mounting;  // From tf, when it connects the two frames.
  bool mirrored = false;  // The scans were mirrored (an upside-down sensor).
  // How often the scans were matched: where they sweep, each pass de-skewed through the previous
  // pass's calibration, until it settled.
  int matching_passes = 1;
  std::optional<BeamTimingCheck> beam_timing;  // The check of the beams' timing, once made.
  std::vector<std::string> warnings;
  // What calib did to the recording that is no problem of it (beams on the robot's body left
  // out, logs joined): in the summary and the JSON, not in the verdict.
  std::vector<std::string> notes;
  // The calibrated heading against the building's walls (wall_check.h), once calibrated.
  std::optional<WallCheck> walls;
};

StatusOr<RobotBagLog> LaserLogFromRobotMessages(const RobotMessages& bag,
                                                const RobotBagOptions& options = {});

struct RobotBagCalibration {
  RobotBagLog log;           // Of the last pass.
  LaserTimingResult result;  // The timing-aware calibration of the last pass (two-stage).
  // The refinement against the scan points, when asked for and possible (else a warning in
  // scan_point_warnings says why).
  std::optional<ScanPointCalibration> scan_points;
  std::vector<std::string> scan_point_warnings;
  // Why the two-stage route could not calibrate the bag ("" when it did): `result` then holds the
  // scan points' result alone (CalibrateOnScanPointsAlone).
  std::string two_stage_failed;
};

// The bag's laser calibration, with its timing. Where the scans sweep (beams at their own times),
// further passes match them again, each de-skewed through the previous pass's calibration, until
// no parameter moves by 0.1 σ (at most 8 passes; a warning otherwise): without a second pass a
// 10 Hz sweep of a robot at 0.5 m/s put b 4.6 σ off on a 600-scan log, and with only two, fast
// turns (0.5 rad per sweep) put sensor_x 4σ off. A long log's passes before the last run on its
// first 3000 scans.
StatusOr<RobotBagCalibration> CalibrateRobotMessages(const RobotMessages& bag,
                                                     const RobotBagOptions& options,
                                                     const LaserTimingOptions& timing);

// When each of `scans` (the bag's scan topic) was taken on the wheels' clock, by `timing`: its
// estimated sample time where the timing placed it (by record), else its stamp + the timing's
// offset. Where the timing hardly determined the offset (σ over a quarter of the scan period: few
// intervals, e.g. a corridor's degenerate matches) it places none (start_s empty).
SweepStarts ScanSweepStarts(const std::vector<LaserScan>& scans, const LaserTimingResult& timing);

// A laser scan seen from its mirror image (y → −y): the scans of a sensor mounted upside down,
// in a frame whose z axis points up like the base's. Every angle changes sign (the increment
// too: the beams turn clockwise there); the beams keep their order, stamp and times, so that the
// sweep is de-skewed as any other.
LaserScan MirroredScan(const LaserScan& scan);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_ROBOT_BAG_LOG_H_
