#ifndef CALIB_TOOLS_REPORT_DEPLOYMENT_H_
#define CALIB_TOOLS_REPORT_DEPLOYMENT_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/status.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>
#include <calib/solvers/timing/laser_timing_calibration.h>

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

// A calibration in the terms a robot's configuration uses (`calib calibrate --export`): the
// diff_drive_controller's wheel parameters, the sensor's static transform and URDF joint origin,
// and the offset a driver adds to the sensor's stamps.
namespace calib {

struct Deployment {
  double left_wheel_radius_m = 0.0, right_wheel_radius_m = 0.0, wheel_separation_m = 0.0;
  double left_wheel_radius_stddev_m = 0.0, right_wheel_radius_stddev_m = 0.0;
  double wheel_separation_stddev_m = 0.0;
  // x, y and yaw calibrated; z, roll and pitch from tf when the log has it (else 0: a planar
  // calibration cannot see them).
  Eigen::Isometry3d base_T_sensor = Eigen::Isometry3d::Identity();
  double sensor_x_stddev_m = 0.0, sensor_y_stddev_m = 0.0, sensor_yaw_stddev_rad = 0.0;
  bool sensor_height_from_tf = false;
  std::string base_frame = "base_link", sensor_frame = "laser";
  // A sensor sample stamped t was taken at t + offset (odometry clock); empty: not estimated.
  std::optional<double> time_offset_s;
  double time_offset_stddev_s = 0.0;
  bool offset_expressible = true;  // False for a free-running sensor clock.
  std::string source;              // The input it was calibrated from.
  std::vector<std::string> notes;  // What the configuration cannot express, caveats.
};

// The laser calibration `result`; `recording`: the bag it came from (frames, the height and tilt
// from tf), `timing`: its latent-time calibration (the stamps' offset), both optional.
Deployment LaserDeployment(const LaserCalibrationResult& result, const std::string& source,
                           const RobotBagLog* recording = nullptr,
                           const LaserTimingResult* timing = nullptr,
                           const ScanPointCalibration* scan_points = nullptr);

// The bearing calibration in robot terms: wheel radius × δR, δL, wheelbase × δB, the camera at
// (ρ cos φ, ρ sin φ) with yaw φ + ψ. Needs the metric set (an initial distance in meta.json).
StatusOr<Deployment> BearingDeployment(const BearingCalibrationResult& result,
                                       const BearingLog& log, const std::string& source);

// The --export formats: "yaml", "urdf", "tf", comma-separated, or "all".
StatusOr<std::vector<std::string>> ParseExportFormats(const std::string& formats);

// diff_drive_controller parameters (wheel_radius = the mean radius, the left/right multipliers
// make each wheel's own) plus the plain values and the mounting; YAML.
std::string DeploymentYaml(const Deployment& deployment);
// The sensor's fixed joint (URDF <joint> with its <origin>).
std::string DeploymentUrdf(const Deployment& deployment);
// `ros2 run tf2_ros static_transform_publisher` arguments: x y z yaw pitch roll parent child.
std::string DeploymentStaticTransform(const Deployment& deployment);

// Writes each format beside `output` (OUT.json → OUT.yaml, OUT.urdf, OUT.tf.txt), or in the
// working directory as calib_calibration.* when there is no output file (or it is a device or a
// pipe); returns the paths.
StatusOr<std::vector<std::string>> WriteDeployment(const Deployment& deployment,
                                                   const std::vector<std::string>& formats,
                                                   const std::string& output);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_DEPLOYMENT_H_
