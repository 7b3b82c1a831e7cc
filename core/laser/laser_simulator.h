#ifndef CALIB_CORE_LASER_LASER_SIMULATOR_H_
#define CALIB_CORE_LASER_LASER_SIMULATOR_H_

#include <calib/core/diff_drive.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/se2.h>
#include <calib/core/timing/logging_model.h>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

// Simulated laser–odometry logs with known truth, for tests, benchmarks and diagnosis. The robot
// is integrated finely in continuous time, so physical effects that the base model leaves out
// (CONTRACT.md, `calib diagnose`) appear in the data as they would on a real robot.
namespace calib {

enum class LaserTrajectory {
  kRich,          // Straight runs, pure rotations and arcs of both signs, smooth speed changes.
  kStraight,      // Only straight driving (no turning).
  kPureRotation,  // Only turning on the spot (v = 0).
  kConstantArc,   // One arc at constant wheel speeds.
};

// Effects of the contract's `calib diagnose`; zero means absent.
struct LaserEffects {
  double time_offset_s = 0.0;        // A scan stamped t was taken at t + offset (odometry clock).
  double lateral_slip_s = 0.0;       // Lateral velocity = γ·v·ω (+y left).
  double longitudinal_slip_s = 0.0;  // Forward velocity = v − γ·dv/dt.
  double radius_change_time_s = -1;  // < 0: no change. Otherwise radii switch at this time.
  double left_radius_after_m = 0.0;
  double right_radius_after_m = 0.0;
};

struct LaserSimOptions {
  OdometryParams odometry{0.0206, 0.0207, 0.088};
  Pose2d base_T_sensor = Pose2d(-0.005, 0.006, -1.55);
  int num_intervals = 1000;
  double mean_interval_s = 0.8;
  double interval_jitter_s = 0.02;  // Uniform ± jitter on each interval length.
  LaserTrajectory trajectory = LaserTrajectory::kRich;
  double max_wheel_speed = 0.5;  // rad/s, the largest commanded wheel speed.
  // Khepera-like speed changes: wheel speeds follow commanded targets through a first-order lag.
  double speed_time_constant_s = 0.5;
  double segment_mean_s = 6.0;  // Mean time between new commanded targets.
  Eigen::Vector3d scan_noise_sigma = Eigen::Vector3d(0.001, 0.001, 0.002);  // x, y (m), θ (rad).
  double outlier_fraction = 0.0;       // Intervals whose scan match is replaced by a slip outlier.
  double outlier_scale = 20.0;         // Outlier error in multiples of the scan noise sigma.
  double encoder_ticks_per_rad = 0.0;  // > 0: cumulative wheel angles are quantized.
  double wheel_speed_noise = 0.0;      // Std of white noise added to the reported φ (rad/s).
  int record_steps = 0;  // > 0: store this many encoder sub-steps per interval in `steps`.
  // Shortest quadrature panel; panels otherwise break at every speed target, scan time and
  // radius change and span at most half of min(speed time constant, 1/ω).
  double integration_step_s = 0.002;
  LaserEffects effects;
  uint64_t seed = 1;
};

struct LaserSimTruth {
  OdometryParams odometry;
  Pose2d base_T_sensor = Pose2d::Zero();
  LaserEffects effects;
  std::vector<bool> is_outlier;  // Per interval.
};

// A log of consecutive intervals (has_timestamps = true, start_s on the odometry clock).
LaserLog SimulateLaserLog(const LaserSimOptions& options, LaserSimTruth* truth = nullptr);

// Keeps only the intervals that do not drive backward (v ≥ 0 for the given odometry), marking the
// interval after each dropped run with gap_before: a forward-only robot, on which a lateral slip
// γ·v·ω cannot cancel between directions.
std::vector<LaserInterval> DropBackwardIntervals(const std::vector<LaserInterval>& intervals,
                                                 const OdometryParams& odometry);

// The same motion as raw streams: encoder samples at `encoder_rate_hz` and scan-matcher poses
// (world_T_sensor, noisy, one per interval end), for the stream reader (LaserStreams is in
// laser_log.h).
LaserStreams SimulateLaserStreams(const LaserSimOptions& options, double encoder_rate_hz,
                                  LaserSimTruth* truth = nullptr);

// The same motion as a real robot logs it (core/timing/logging_model.h): the sensor's true samples
// are the scan times (its own grid when it free-runs: options.num_intervals + 1 samples, and
// mean_interval_s/interval_jitter_s are unused), each logger row holds the latest sample picked
// up and its pick-up stamp, and encoder rows hold the cumulative wheel angles at the true poll
// times under scattered stamps. `timing` receives the true time of every row. With every logging
// field zero the output equals SimulateLaserStreams(options, 0.0, truth).
LaserStreams SimulateLoggedLaserStreams(const LaserSimOptions& options, const LoggingModel& model,
                                        LaserSimTruth* truth = nullptr,
                                        LoggedTimingTruth* timing = nullptr);

// An incremental scan matcher's noise on exact poses: each displacement between consecutive
// distinct samples gets its own N(0, σ²) composed at its end, pose_k = pose_{k−1} ∘ (true motion)
// ∘ noise, so errors accumulate as in chained ICP and consecutive displacements are independent
// (MeasuredSensorPoses' independent pose noise makes them correlated by −1/2). A row holding the
// same sample as the row before (`sample_index`, one per row; empty: every row its own) keeps its
// pose.
void ChainScanMatcherNoise(const Eigen::Vector3d& sigma, const std::vector<size_t>& sample_index,
                           uint64_t seed, std::vector<StampedPose>* poses);

}  // namespace calib

#endif  // CALIB_CORE_LASER_LASER_SIMULATOR_H_
