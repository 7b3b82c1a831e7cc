// The timing-free consistency check: exact on noise-free data, honest σ on clean noisy data, and a
// warning when the calibration is biased (a wrong wheelbase, stamps that are not sample times).
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/random.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_consistency.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace calib {
namespace {

const OdometryParams kOdometry{0.0206, 0.0207, 0.088};
const Pose2d kMounting(-0.005, 0.006, -1.55);
const Eigen::Vector3d kNoise(0.001, 0.001, 0.002);

// A robot that turns mostly left (net rotation of many turns, as a real robot driving loops):
// constant wheel speeds within each interval, held for a few intervals, with a rest of three
// intervals every `rest_every` (0: never). Scan noise kNoise·noise_scale.
std::vector<LaserInterval> DriveLoops(int n, uint64_t seed, double noise_scale, int rest_every) {
  Random random(seed);
  std::vector<LaserInterval> intervals(n);
  Eigen::Vector2d speed = Eigen::Vector2d::Zero();
  for (int k = 0; k < n; ++k) {
    LaserInterval& in = intervals[k];
    in.start_s = k > 0 ? intervals[k - 1].start_s + intervals[k - 1].duration_s : 0.0;
    in.duration_s = random.Uniform(0.7, 0.9);
    if (k % 4 == 0) {
      speed << random.Uniform(-0.3, 0.5), random.Uniform(-0.2, 0.6);
    }
    const bool rest = rest_every > 0 && k % rest_every < 3;
    in.left_speed = rest ? 0.0 : speed(0);
    in.right_speed = rest ? 0.0 : speed(1);
    const Pose2d robot = WheelStepDisplacement(kOdometry.left_radius_m, kOdometry.right_radius_m,
                                               kOdometry.wheelbase_m, in.left_speed * in.duration_s,
                                               in.right_speed * in.duration_s);
    in.sensor_motion = SensorMotionFromRobotMotion(kMounting, robot);
    for (int j = 0; j < 3; ++j) in.sensor_motion(j) += noise_scale * kNoise(j) * random.Normal();
    in.record = k + 1;
  }
  return intervals;
}

// Stamps that are not sample times: the wheel rotation attributed to each interval runs from
// t_k + ε_k to t_{k+1} + ε_{k+1}, ε of σ `jitter_s`; the sensor saw the true intervals. The
// increments only move between neighbours, so every total inside the log is unchanged.
std::vector<LaserInterval> ShiftWheelIncrements(std::vector<LaserInterval> intervals,
                                                double jitter_s, uint64_t seed) {
  Random random(seed);
  std::vector<Eigen::Vector2d> moved(intervals.size() + 1, Eigen::Vector2d::Zero());
  for (size_t k = 1; k < intervals.size(); ++k) {
    const Eigen::Vector2d rate(intervals[k - 1].left_speed + intervals[k].left_speed,
                               intervals[k - 1].right_speed + intervals[k].right_speed);
    moved[k] = rate / 2.0 * jitter_s * random.Normal();  // From interval k to interval k − 1.
  }
  for (size_t k = 0; k < intervals.size(); ++k) {
    LaserInterval& in = intervals[k];
    const Eigen::Vector2d shift = moved[k + 1] - moved[k];
    in.left_speed += shift(0) / in.duration_s;
    in.right_speed += shift(1) / in.duration_s;
  }
  return intervals;
}

LaserConsistency Check(const std::vector<LaserInterval>& intervals,
                       const LaserCalibrationResult& result, const LaserCalibration& estimate,
                       const LaserConsistencyOptions& options = {}) {
  return CheckLaserConsistency(intervals, estimate, result.covariance, result.noise_sigma[0],
                               result.is_inlier[0], options);
}

TEST(LaserConsistencyTest, NoiseFreeSimulationAgreesExactly) {
  LaserSimOptions options;
  options.scan_noise_sigma.setZero();
  options.num_intervals = 500;
  const LaserLog log = SimulateLaserLog(options);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  const LaserConsistency& check = result->consistency;
  ASSERT_TRUE(check.checked) << check.note;
  ASSERT_FALSE(check.windows.empty());
  EXPECT_TRUE(check.warnings.empty());
  for (const LaserConsistencyWindow& w : check.windows) {
    // Rotation is linear in the wheel rotation; the travel's arc length holds within an interval
    // whose curvature changes up to the second order of that change.
    EXPECT_NEAR(w.rotation.measured, w.rotation.predicted, 1e-9);
    EXPECT_NEAR(w.translation.measured, w.translation.predicted, 1e-7);
    EXPECT_GT(std::abs(w.rotation.measured), 0.1);
  }
}

}  // namespace
}  // namespace calib
