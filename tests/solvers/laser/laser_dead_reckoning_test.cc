#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_dead_reckoning.h>
#include <gtest/gtest.h>

#include <cmath>

namespace calib {
namespace {

LaserSimOptions ExactModel(int intervals) {
  LaserSimOptions sim;
  sim.num_intervals = intervals;
  sim.speed_time_constant_s = 0.0;  // Constant speeds per interval: the model is exact.
  return sim;
}

TEST(LaserDeadReckoningTest, TrueParametersRetraceANoiseFreeScanPath) {
  LaserSimOptions sim = ExactModel(300);
  sim.scan_noise_sigma.setZero();
  const LaserLog log = SimulateLaserLog(sim);
  const std::vector<Pose2d> scan = ScanMatchedSensorPath(log.intervals);
  const std::vector<Pose2d> wheels =
      DeadReckonedSensorPath(log.intervals, sim.odometry, sim.base_T_sensor);
  ASSERT_EQ(scan.size(), log.intervals.size() + 1);
  ASSERT_EQ(wheels.size(), scan.size());
  EXPECT_EQ(scan.front(), Pose2d::Zero());
  for (size_t k = 0; k < scan.size(); ++k) {
    EXPECT_LT((scan[k] - wheels[k]).cwiseAbs().maxCoeff(), 1e-9) << k;
  }
  for (const Eigen::Vector3d& e :
       LaserIntervalErrors(log.intervals, {sim.odometry, sim.base_T_sensor})) {
    EXPECT_LT(e.cwiseAbs().maxCoeff(), 1e-12);
  }
}

// The mean distance between two paths over their poses.
double MeanGap(const std::vector<Pose2d>& a, const std::vector<Pose2d>& b) {
  double sum = 0.0;
  for (size_t k = 0; k < a.size(); ++k) sum += (a[k] - b[k]).head<2>().norm();
  return sum / a.size();
}

// A robot whose driver believes a 3 % larger left wheel, a 2 % smaller right one and a 6 %
// shorter wheelbase: with the calibrated parameters the dead-reckoned path stays and ends much
// closer to the scan-matched one. A robot of 0.1 m wheels and 0.5 m wheelbase at up to 0.5 m/s
// (the Khepera of the sample log covers a few metres in millimetre steps, where the paths' own
// random walk hides a few per cent of wheel error).
TEST(LaserDeadReckoningTest, CalibratedPathEndsCloserThanAWrongNominal) {
  LaserSimOptions sim = ExactModel(600);
  sim.odometry = {0.1, 0.1, 0.5};
  sim.base_T_sensor = Pose2d(0.2, 0.05, 0.1);
  sim.max_wheel_speed = 5.0;
  sim.outlier_fraction = 0.05;
  sim.seed = 7;
  const LaserLog log = SimulateLaserLog(sim);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  LaserCalibration nominal = result->estimate;
  nominal.odometry = {sim.odometry.left_radius_m * 1.03, sim.odometry.right_radius_m * 0.98,
                      sim.odometry.wheelbase_m * 0.94};
  const LaserPathComparison paths =
      CompareLaserPaths(log.intervals, nominal, result->estimate, result->is_inlier[0]);
  const double nominal_end = (paths.before.back() - paths.scan_matched.back()).head<2>().norm();
  const double calibrated_end =
      (paths.calibrated.back() - paths.scan_matched.back()).head<2>().norm();
  EXPECT_LT(calibrated_end, 0.25 * nominal_end)
      << "calibrated " << calibrated_end << " m, nominal " << nominal_end << " m";
  const double nominal_mean = MeanGap(paths.before, paths.scan_matched);
  const double calibrated_mean = MeanGap(paths.calibrated, paths.scan_matched);
  EXPECT_LT(calibrated_mean, 0.25 * nominal_mean)
      << "calibrated " << calibrated_mean << " m, nominal " << nominal_mean << " m";
}

TEST(LaserDeadReckoningTest, OutliersTakeTheSameStepInEveryPath) {
  LaserSimOptions sim = ExactModel(50);
  sim.scan_noise_sigma.setZero();
  LaserLog log = SimulateLaserLog(sim);
  log.intervals[10].sensor_motion += Pose2d(0.5, -0.3, 0.4);  // A gross bad match.
  std::vector<bool> used(log.intervals.size(), true);
  used[10] = false;
  const LaserCalibration truth{sim.odometry, sim.base_T_sensor};
  const LaserPathComparison paths = CompareLaserPaths(log.intervals, truth, truth, used);
  EXPECT_LT((paths.scan_matched.back() - paths.calibrated.back()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((paths.before.back() - paths.calibrated.back()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(LaserDeadReckoningTest, SpeedsAndInlierCut) {
  LaserInterval k;
  k.duration_s = 1.0;
  k.left_speed = 2.0;
  k.right_speed = 4.0;
  const std::vector<Eigen::Vector2d> speeds = IntervalRobotSpeeds({k}, {0.1, 0.1, 0.5});
  EXPECT_DOUBLE_EQ(speeds[0](0), 0.3);  // (0.2 + 0.4)/2 m/s.
  EXPECT_DOUBLE_EQ(speeds[0](1), 0.4);  // (0.4 − 0.2)/0.5 rad/s.
  const std::vector<bool> inlier = ClassifyLaserInliers(
      {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(4.1, 0, 0)}, Eigen::Vector3d::Ones());
  EXPECT_TRUE(inlier[0]);
  EXPECT_FALSE(inlier[1]);  // 16.81 > 16.27.
}

}  // namespace
}  // namespace calib
