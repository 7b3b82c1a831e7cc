#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/laser/laser_dead_reckoning.h>

namespace calib {

std::vector<Pose2d> ScanMatchedSensorPath(const std::vector<LaserInterval>& intervals) {
  std::vector<Pose2d> path = {Pose2d::Zero()};
  for (const LaserInterval& interval : intervals) {
    path.push_back(Compose(path.back(), interval.sensor_motion));
  }
  return path;
}

std::vector<Pose2d> DeadReckonedSensorPath(const std::vector<LaserInterval>& intervals,
                                           const OdometryParams& odometry,
                                           const Pose2d& base_T_sensor) {
  std::vector<Pose2d> path = {Pose2d::Zero()};
  for (const LaserInterval& interval : intervals) {
    const Pose2d robot_motion = IntervalRobotMotion(odometry.left_radius_m, odometry.right_radius_m,
                                                    odometry.wheelbase_m, interval);
    path.push_back(Compose(path.back(), SensorMotionFromRobotMotion(base_T_sensor, robot_motion)));
  }
  return path;
}

LaserPathComparison CompareLaserPaths(const std::vector<LaserInterval>& intervals,
                                      const LaserCalibration& before,
                                      const LaserCalibration& calibrated,
                                      const std::vector<bool>& used) {
  const auto sensor_motion = [](const LaserCalibration& c, const LaserInterval& interval) {
    const Pose2d robot_motion = IntervalRobotMotion(
        c.odometry.left_radius_m, c.odometry.right_radius_m, c.odometry.wheelbase_m, interval);
    return SensorMotionFromRobotMotion(c.base_T_sensor, robot_motion);
  };
  LaserPathComparison paths;
  paths.scan_matched = paths.before = paths.calibrated = {Pose2d::Zero()};
  for (size_t k = 0; k < intervals.size(); ++k) {
    const Pose2d predicted = sensor_motion(calibrated, intervals[k]);
    const bool outlier = k < used.size() && !used[k];
    paths.scan_matched.push_back(
        Compose(paths.scan_matched.back(), outlier ? predicted : intervals[k].sensor_motion));
    paths.before.push_back(
        Compose(paths.before.back(), outlier ? predicted : sensor_motion(before, intervals[k])));
    paths.calibrated.push_back(Compose(paths.calibrated.back(), predicted));
  }
  return paths;
}

std::vector<Eigen::Vector3d> LaserIntervalErrors(const std::vector<LaserInterval>& intervals,
                                                 const LaserCalibration& calibration) {
  const double odometry[3] = {calibration.odometry.left_radius_m,
                              calibration.odometry.right_radius_m,
                              calibration.odometry.wheelbase_m};
  const SensorMounting mounting(calibration.base_T_sensor.data());
  std::vector<Eigen::Vector3d> errors;
  errors.reserve(intervals.size());
  for (const LaserInterval& interval : intervals) {
    errors.push_back(LaserResidual::Error(interval, odometry, mounting));
  }
  return errors;
}

std::vector<Eigen::Vector2d> IntervalRobotSpeeds(const std::vector<LaserInterval>& intervals,
                                                 const OdometryParams& odometry) {
  std::vector<Eigen::Vector2d> speeds;
  speeds.reserve(intervals.size());
  for (const LaserInterval& k : intervals) {
    const double left = odometry.left_radius_m * k.left_speed;
    const double right = odometry.right_radius_m * k.right_speed;
    speeds.emplace_back(0.5 * (left + right), (right - left) / odometry.wheelbase_m);
  }
  return speeds;
}

std::vector<bool> ClassifyLaserInliers(const std::vector<Eigen::Vector3d>& errors,
                                       const Eigen::Vector3d& noise_sigma, double chi2) {
  std::vector<bool> inlier;
  inlier.reserve(errors.size());
  for (const Eigen::Vector3d& e : errors) {
    inlier.push_back(e.cwiseQuotient(noise_sigma).squaredNorm() <= chi2);
  }
  return inlier;
}

}  // namespace calib
