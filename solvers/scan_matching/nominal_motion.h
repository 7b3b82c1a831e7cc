#ifndef CALIB_SOLVERS_SCAN_MATCHING_NOMINAL_MOTION_H_
#define CALIB_SOLVERS_SCAN_MATCHING_NOMINAL_MOTION_H_

#include <calib/core/diff_drive.h>
#include <calib/core/encoder_sample.h>
#include <calib/core/se2.h>
#include <calib/solvers/scan_matching/scan_points.h>

#include <cmath>
#include <vector>

// The sensor's motion from the wheel angles through given (nominal or calibrated) wheels and
// mounting: the scan matcher's guesses and the de-skewing of each sweep.
namespace calib {

struct WheelsAndMounting {
  OdometryParams wheels{0.0, 0.0, 0.0};
  Pose2d base_T_sensor = Pose2d::Zero();
  // A zero radius or wheelbase gives no motion to go by.
  bool known() const;
};

// When each scan's sweep began on the wheels' clock: where a timing calibration placed the scan,
// start_s[i] (per scan of the input; NaN where it did not), else its stamp + offset_s. Pick-up
// stamps lag their samples by anything up to a period: one offset for all misplaced the sweeps
// of a logger slower than its sensor by ±50 ms, enough for the beam-timing check to take another
// timing in fast turns.
struct SweepStarts {
  double offset_s = 0.0;
  std::vector<double> start_s;
  double operator()(size_t i, double stamp_s) const {
    return i < start_s.size() && std::isfinite(start_s[i]) ? start_s[i] : stamp_s + offset_s;
  }
};

// The sensor's displacement between two times (the wheel angles interpolated, one arc).
Pose2d SensorMotionBetween(const std::vector<EncoderSample>& encoders, double from_s, double to_s,
                           const WheelsAndMounting& robot);

// The sensor's motion over [from, from + sweep]: one piece per encoder step (the wheel angles are
// linear between samples), so that the robot's accelerations within the sweep are followed.
// Beyond the encoders' span the nearest step's velocity goes on (a sweep that outlasts the log's
// last sample is not taken as a stop).
SweepMotion SweepMotionOver(const std::vector<EncoderSample>& encoders, double from_s,
                            double sweep_s, const WheelsAndMounting& robot);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_NOMINAL_MOTION_H_
