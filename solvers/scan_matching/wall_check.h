#ifndef CALIB_SOLVERS_SCAN_MATCHING_WALL_CHECK_H_
#define CALIB_SOLVERS_SCAN_MATCHING_WALL_CHECK_H_

#include <calib/core/diff_drive.h>
#include <calib/core/encoder_sample.h>
#include <calib/core/scan/laser_scan.h>

#include <Eigen/Core>
#include <optional>
#include <vector>

// The building's walls as a compass for a calibrated heading, with no scan matching: indoors the
// walls meet at right angles, so the heading the wheels give plus the direction of the walls in
// each scan (mod 90°) is the walls' direction in the building, the same all along a log where the
// heading is right. A radius ratio or a wheelbase that is off turns it steadily (on every
// straight, or with every turn).
namespace calib {

// The direction of the walls in the scan's frame, mod 90° in [−45°, 45°), from chords of about
// 30 cm between beams that run straight (the middle beam within 1 cm and 5 % of the chord's
// length of it); nullopt when such chords agree on a direction over less than 1 m in all.
std::optional<double> WallDirectionRad(const LaserScan& scan);

// How the walls' direction moved under one heading: its linear trend over the log (through the
// medians of ten stretches of time, with the trend's σ from their spread about it) and the scatter
// of the scans about that trend (1.4826 × the median absolute deviation).
struct WallHeading {
  double drift_rad = 0.0, drift_stddev_rad = 0.0, scatter_rad = 0.0;
  // The drift's σ from the wheels' own uncertainty (the calibration's covariance): the radius
  // ratio's σ alone turns the walls by several degrees over a long log, so a drift within it is
  // no disagreement. 0 when no covariance is given.
  double calibration_stddev_rad = 0.0;
};

struct WallCheck {
  int scans = 0, scans_with_walls = 0;
  double duration_s = 0.0;
  // Half the scans or more see walls, and under the calibrated heading they scatter by at most
  // 8° about the trend: the walls meet at right angles, and the check holds.
  bool right_angled = false;
  WallHeading calibrated;
  std::optional<WallHeading> nominal;
};

// The scans (stamp order; `mirrored`: an upside-down lidar's, as recorded) against the heading of
// `calibrated` (and of `nominal` when given) from the wheel angles, each scan taken at its stamp
// plus scan_time_offset_s on the wheels' clock. `covariance` (r_l, r_r, b), when given, is the
// calibrated wheels' (WallHeading::calibration_stddev_rad).
WallCheck CheckAgainstWalls(const std::vector<LaserScan>& scans, bool mirrored,
                            const std::vector<EncoderSample>& wheels,
                            const OdometryParams& calibrated,
                            const std::optional<OdometryParams>& nominal, double scan_time_offset_s,
                            const std::optional<Eigen::Matrix3d>& covariance = std::nullopt);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_WALL_CHECK_H_
