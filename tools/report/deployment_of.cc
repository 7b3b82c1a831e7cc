// Deployments built from the calibrations of both problems (see deployment.h).
#include <calib/tools/report/deployment.h>

#include <cmath>

namespace calib {
namespace {

Eigen::Isometry3d PlanarPose(double x, double y, double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, 0.0);
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return pose;
}

// The calibrated x, y, yaw on tf's mounting: its height and tilt kept, its yaw turned by the
// calibrated correction about the base's z axis.
Eigen::Isometry3d OnTfMounting(const Pose2d& calibrated, const PlanarMounting& nominal) {
  Eigen::Isometry3d pose = nominal.base_T_sensor_3d;
  const double turn = calibrated(2) - nominal.base_T_sensor(2);
  pose.linear() = Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ()) * pose.linear();
  pose.translation().x() = calibrated(0);
  pose.translation().y() = calibrated(1);
  return pose;
}

}  // namespace

Deployment LaserDeployment(const LaserCalibrationResult& result, const std::string& source,
                           const RobotBagLog* recording, const LaserTimingResult* timing,
                           const ScanPointCalibration* scan_points) {
  Deployment d;
  d.source = source;
  const LaserCalibration& c = result.estimate;
  const LaserParamVector& s = result.stddev;
  d.left_wheel_radius_m = c.odometry.left_radius_m;
  d.right_wheel_radius_m = c.odometry.right_radius_m;
  d.wheel_separation_m = c.odometry.wheelbase_m;
  d.left_wheel_radius_stddev_m = s(0);
  d.right_wheel_radius_stddev_m = s(1);
  d.wheel_separation_stddev_m = s(2);
  d.sensor_x_stddev_m = s(3);
  d.sensor_y_stddev_m = s(4);
  d.sensor_yaw_stddev_rad = s(5);
  d.base_T_sensor = PlanarPose(c.base_T_sensor(0), c.base_T_sensor(1), c.base_T_sensor(2));
  if (recording) {
    if (!recording->base_frame.empty()) d.base_frame = recording->base_frame;
    if (!recording->sensor_frame.empty()) d.sensor_frame = recording->sensor_frame;
    if (recording->nominal_mounting) {
      d.base_T_sensor = OnTfMounting(c.base_T_sensor, *recording->nominal_mounting);
      d.sensor_height_from_tf = true;
    }
  }
  if (timing != nullptr && timing->sensor_clock == "free_running") {
    d.offset_expressible = false;
    d.notes.push_back(
        "the sensor free-runs on its own clock (period " + std::to_string(timing->sensor_period_s) +
        " s): a constant offset on its stamps cannot express that; stamp scans at acquisition");
  } else if (timing != nullptr) {
    d.time_offset_s = timing->time_offset_s;
    d.time_offset_stddev_s = timing->time_offset_stddev_s;
    if (scan_points != nullptr) {
      // δ is measured from the times the timing calibration gave the scans.
      *d.time_offset_s += scan_points->time_offset_s;
      d.time_offset_stddev_s =
          std::hypot(d.time_offset_stddev_s, scan_points->time_offset_stddev_s);
    }
  }
  return d;
}

StatusOr<Deployment> BearingDeployment(const BearingCalibrationResult& result,
                                       const BearingLog& log, const std::string& source) {
  if (!result.has_metric) {
    return Status::InvalidInput(
        source +
        ": --export needs the metric scale: without an initial distance in meta.json the log "
        "determines only eta, delta and xi (ratios), not the wheel radii, the wheelbase or where "
        "the camera sits");
  }
  const BearingMetricParams& m = result.metric;
  const BearingMetricVector& s = result.metric_stddev;  // φ, ψ, ρ, δR, δL, δB.
  Deployment d;
  d.source = source;
  d.sensor_frame = "camera";
  d.left_wheel_radius_m = log.meta.wheel_radius_m * m.delta_l;
  d.right_wheel_radius_m = log.meta.wheel_radius_m * m.delta_r;
  d.wheel_separation_m = log.meta.wheelbase_m * m.delta_b;
  d.left_wheel_radius_stddev_m = log.meta.wheel_radius_m * s(4);
  d.right_wheel_radius_stddev_m = log.meta.wheel_radius_m * s(3);
  d.wheel_separation_stddev_m = log.meta.wheelbase_m * s(5);
  const double x = m.rho_m * std::cos(m.phi_rad), y = m.rho_m * std::sin(m.phi_rad);
  d.base_T_sensor = PlanarPose(x, y, m.phi_rad + m.psi_rad);
  const BearingMetricMatrix& cov = result.metric_covariance;
  // x = ρ cos φ, y = ρ sin φ, yaw = φ + ψ, to first order.
  const Eigen::Vector3d jx(-y, 0.0, std::cos(m.phi_rad)), jy(x, 0.0, std::sin(m.phi_rad));
  const Eigen::Matrix3d c = cov.topLeftCorner<3, 3>();
  d.sensor_x_stddev_m = std::sqrt(std::max(0.0, jx.dot(c * jx)));
  d.sensor_y_stddev_m = std::sqrt(std::max(0.0, jy.dot(c * jy)));
  d.sensor_yaw_stddev_rad = std::sqrt(std::max(0.0, cov(0, 0) + 2 * cov(0, 1) + cov(1, 1)));
  if (result.timing.time_offset_modelled) {
    d.time_offset_s = result.timing.time_offset_s;
    d.time_offset_stddev_s = result.timing.time_offset_stddev_s;
  }
  d.notes.push_back(
      "the camera frame is x forward (REP 103 camera_link, not the optical frame): its yaw is "
      "the direction of bearing 0 in the robot frame");
  return d;
}

}  // namespace calib
