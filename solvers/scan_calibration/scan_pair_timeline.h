#ifndef CALIB_SOLVERS_SCAN_CALIBRATION_SCAN_PAIR_TIMELINE_H_
#define CALIB_SOLVERS_SCAN_CALIBRATION_SCAN_PAIR_TIMELINE_H_

#include <calib/core/diff_drive.h>
#include <calib/core/encoder_sample.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/se2.h>

#include <vector>

// The wheels between two times as constant-speed steps (the encoder samples are the knots, the
// angles linear between them), and where any time in between falls among them.
namespace calib {

struct PairTimeline {
  std::vector<double> knot_time_s;  // t₀, the encoder times strictly inside, t_end.
  std::vector<WheelStep> steps;     // One fewer than the knots.

  // The step that t_s falls in and the fraction of it done (clamped to [t₀, t_end]); the last
  // knot is (steps.size(), 0).
  void Locate(double t_s, int* step, double* fraction) const;
  double StepSeconds(int step) const { return knot_time_s[step + 1] - knot_time_s[step]; }
};

// `encoders` sorted by time and non-empty; t₀ < t_end.
PairTimeline MakePairTimeline(const std::vector<EncoderSample>& encoders, double t0_s,
                              double t_end_s);

// base_{t₀}_T_base at every knot for the given wheels.
std::vector<Pose2d> KnotPoses(const PairTimeline& timeline, const OdometryParams& odometry);

// laser_{t₀}_T_laser_t: the laser's motion from t₀ to t through the wheels and the mounting.
Pose2d LaserMotion(const PairTimeline& timeline, const std::vector<Pose2d>& knot_poses,
                   const LaserCalibration& calibration, double t_s);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_CALIBRATION_SCAN_PAIR_TIMELINE_H_
