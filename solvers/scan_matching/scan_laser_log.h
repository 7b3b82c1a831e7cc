#ifndef CALIB_SOLVERS_SCAN_MATCHING_SCAN_LASER_LOG_H_
#define CALIB_SOLVERS_SCAN_MATCHING_SCAN_LASER_LOG_H_

#include <calib/core/diff_drive.h>
#include <calib/core/encoder_sample.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/core/se2.h>
#include <calib/core/status.h>
#include <calib/solvers/scan_matching/scan_odometry.h>

#include <string>
#include <vector>

// Raw scans and the encoders to the laser calibration's stream log: the scans are matched into
// sensor poses (ScanOdometry, keyframes, seeded by the odometry), a failed match becomes a gap
// (the scan is left out) and a broken chain a new pose segment (no interval spans it), and the
// poses and wheel angles become the raw streams the calibration reads.
namespace calib {

struct ScanLogOptions {
  ScanOdometryOptions matching;
  // The odometry's guesses for the matcher come from these nominal values (the wheel angles
  // between two scans through one arc, then the mounting); a zero radius gives no guess (no
  // motion), which the matcher handles at scan rates where the robot moves a few cm per scan.
  OdometryParams nominal{0.0, 0.0, 0.0};
  Pose2d nominal_base_T_sensor = Pose2d::Zero();
  // With a nominal radius and beams at their own times: each scan is de-skewed with the
  // sensor's motion over its sweep from the wheels, one piece per encoder step.
  bool deskew = true;
  // When the scans were taken on the wheels' clock (a first calibration's estimate, per input
  // scan): the de-skewing and the matcher's guesses follow the sensor there.
  SweepStarts sweep_starts;
  // A sweep (time_increment × beams) longer than this many scan periods (the median step between
  // the stamps) cannot be, e.g. a time_increment in ms: such scans are taken as instantaneous,
  // with a warning.
  double max_sweep_periods = 1.5;
  // When the matches give no pose stream (no two scans matched, or too few poses), return the log
  // anyway, with the wheel angles, the matching and `unmatched` saying why (for a calibration on
  // the scan points alone) instead of failing.
  bool keep_unmatched = false;
  // Times (the scans' clock) at which the recording starts again (logs joined into one): the
  // matching starts a new pose segment at the first scan from each, so that no interval spans it.
  std::vector<double> restarts_s;
};

struct ScanLog {
  LaserLog log;  // Intervals, the streams (sensor poses with segments) and their timing.
  ScanOdometryResult matching;
  std::vector<int> distinct_scans;  // Per matched scan: its index in the input (repeats skipped).
  int failed_matches = 0, segments = 0, keyframes = 0;
  double matching_seconds = 0.0;
  std::vector<std::string> warnings;
  // With keep_unmatched: why the matches gave no pose stream ("" when they did).
  std::string unmatched;
};

// The names of the input and its two streams in messages ("run.bag", "run.bag /joint_states",
// "run.bag /scan"); the wheel angles' stream and the scans' when empty: source + " (...)".
struct ScanLogNames {
  std::string source, wheels, scans;
};

// The scans must be in stamp order.
StatusOr<ScanLog> LaserLogFromScans(const std::vector<LaserScan>& scans,
                                    const std::vector<EncoderSample>& encoders,
                                    const ScanLogNames& names, const ScanLogOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_SCAN_LASER_LOG_H_
