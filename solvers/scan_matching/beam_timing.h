#ifndef CALIB_SOLVERS_SCAN_MATCHING_BEAM_TIMING_H_
#define CALIB_SOLVERS_SCAN_MATCHING_BEAM_TIMING_H_

#include <calib/core/encoder_sample.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/solvers/scan_matching/nominal_motion.h>
#include <calib/solvers/scan_matching/scan_points.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

// When a spinning lidar measured each beam, as the scans themselves show it. Drivers get this
// wrong: the LDS-01's (TurtleBot3) lists its beams against the order they were measured in and
// gives a time_increment ~18× too small, and a sweep de-skewed the wrong way is skewed twice over.
// Matching two such scans cannot tell (both are skewed alike, and the matcher turns one onto the
// other), but a full circle's own seam can: where the sweep closes, its first and last beams look
// the same way one sweep apart, and only the right timing makes them continue each other's walls.
// The sweeps of the fastest turns are de-skewed under each plausible timing; the one whose seams
// close best wins when it clearly does.
namespace calib {

struct BeamTiming {
  bool reversed = false;          // Measured from the last listed beam to the first.
  double time_increment_s = 0.0;  // Between consecutive beams in the order measured (≥ 0).
  std::string description;        // For messages: "as listed, 0.278 ms apart (the driver's)".
};

// `scan` with its beams listed in the order measured, `timing`'s increment between them (the
// stamp stays the first measured beam's time).
LaserScan WithBeamTiming(const LaserScan& scan, const BeamTiming& timing);

struct BeamTimingCheck {
  BeamTiming recorded, chosen;
  bool changed = false;  // chosen differs from what the driver recorded.
  int scans = 0;         // Scans looked at (few: the robot hardly turned; nothing tested).
  // Per candidate: its timing and the mean capped distance of the seams' points to the lines of
  // the other end (m); empty when nothing was tested (no full circle, too few turns).
  std::vector<std::pair<BeamTiming, double>> candidates;
  std::string warning;  // When changed: what the data say, with the figures.
};

struct BeamTimingOptions {
  int max_scans = 60;  // The scans whose sensor turns most over a scan period (half each way).
  // Below this turn over a scan period a sweep's skew is within the range noise.
  double min_turn_rad = 1.0 * M_PI / 180.0;
  int min_scans = 10;
  // The beams at either end of the sweep compared (they overlap by the turn over a sweep).
  double seam_rad = 45.0 * M_PI / 180.0;
  double cap_m = 0.1;   // A point's distance counts up to this.
  int min_points = 50;  // Compared points each timing needs to be judged.
  // Another timing replaces the driver's when its residual is below this share of the driver's.
  double clear_ratio = 0.8;
};

// `scans` in stamp order (as the calibration reads them, mirrored if upside down), `robot` a first
// calibration, `starts` its estimate of when the scans were taken (on the wheels' clock); `name`
// names the scans in the warning.
BeamTimingCheck CheckBeamTiming(const std::vector<LaserScan>& scans,
                                const std::vector<EncoderSample>& encoders,
                                const WheelsAndMounting& robot, const SweepStarts& starts,
                                const std::string& name, const BeamTimingOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_BEAM_TIMING_H_
