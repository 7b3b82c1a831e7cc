#ifndef CALIB_SOLVERS_TIMING_LASER_TIMING_CALIBRATION_H_
#define CALIB_SOLVERS_TIMING_LASER_TIMING_CALIBRATION_H_

#include <calib/core/laser/laser_simulator.h>
#include <calib/core/status.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

// Timing-aware laser–odometry calibration of raw streams (issue 10, item 2). The true time of
// sensor sample k is t_k = stamp_k + τ + ε_k, ε_k ~ N(0, σ_s²) ("stamps"), or, for a free-running
// sensor that a logger stamps at pick-up, t_k = t0 + P·n_k + a·u_k² ("free_running"); encoder
// sample j was taken at stamp_j + η_j, η_j ~ N(0, σ_e²). The six parameters, τ (or t0, P, a) and
// every latent time are estimated together in one sparse Ceres problem, seeded by the
// stamp-as-truth calibration; σ_s and σ_e are variance components (maximum evidence with the
// latents integrated out); the clock model is chosen by the data (Laplace evidence, AIC for the
// globals). Covariances marginalise the latents and carry the robust-loss correction κ.
//
//   StatusOr<LaserTimingResult> r = CalibrateLaserStreams(streams);
//   if (r.ok()) use(r->calibration.estimate, r->calibration.stddev, r->time_offset_s);
namespace calib {

struct LaserTimingOptions {
  LaserCalibrationOptions calibration;
  std::string sensor_clock = "auto";                        // auto|stamps|free_running.
  std::optional<double> sensor_jitter_s, encoder_jitter_s;  // Fixed σ; empty: estimated.
  bool estimate_offset = true;
  int max_rounds = 4;  // Solve / re-estimate the noise and jitter / re-bracket, at most this often.
};

struct LaserTimingResult {
  LaserCalibrationResult stamps_as_truth;
  LaserCalibrationResult calibration;  // Timing-aware, same struct so reports work.
  double time_offset_s = 0, time_offset_stddev_s = 0;
  double sensor_jitter_s = 0, encoder_jitter_s = 0;
  std::string sensor_clock;  // "stamps" or "free_running": the model chosen.
  double sensor_period_s = 0, sensor_period_stddev_s = 0;
  double clock_drift_s = 0;  // a: the clock's largest departure from a constant period.
  std::vector<double> sample_time_s, sample_time_stddev_s;  // Per distinct sensor sample.
  std::vector<int> sample_record;  // Its 1-based record in the input sensor stream.
  std::vector<int> sample_line;    // Its line in sensor_poses.csv (0: not from a file).
  // The distinct samples of both streams at their estimated times (original clock), time-ordered:
  // the intervals built from them carry the timing model (diagnose searches on them).
  LaserStreams timed_streams;
  int held_repeats_dropped = 0;
  int outside_encoder_span = 0;  // Sensor samples stamped beyond the encoders' span (not used).
  int intervals = 0;
  // Lag-1 correlation (x, y, θ) of the errors of intervals that share a sample; pose_errors: near
  // −1/2, the scan poses err independently and the covariance carries the lag-1 term.
  Eigen::Vector3d neighbour_correlation = Eigen::Vector3d::Zero();
  bool pose_errors = false;
  // −2 log evidence (Laplace) + 2·globals of each model tried; lower is better.
  std::optional<double> stamps_score;  // Empty when pick-up stamps ruled the stamp model out.
  std::optional<double> free_running_score;
  int rounds = 0;
  std::vector<std::string> warnings;
  double seconds = 0;
};

StatusOr<LaserTimingResult> CalibrateLaserStreams(const LaserStreams& streams,
                                                  const LaserTimingOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_LASER_TIMING_CALIBRATION_H_
