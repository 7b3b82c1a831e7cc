#ifndef CALIB_CORE_LASER_LASER_PARAMS_H_
#define CALIB_CORE_LASER_LASER_PARAMS_H_

#include <calib/core/diff_drive.h>
#include <calib/core/param_info.h>
#include <calib/core/se2.h>

#include <Eigen/Core>
#include <array>
#include <string>

namespace calib {

// The six parameters of the laser–odometry problem, in the contract's order and names.
inline constexpr int kNumLaserParams = 6;
inline const std::array<std::string, kNumLaserParams> kLaserParamNames = {
    "r_l", "r_r", "b", "sensor_x", "sensor_y", "sensor_theta"};
// Index, name, unit and reading of each parameter, in the same order.
enum LaserParamIndex { kLaserRl = 0, kLaserRr, kLaserB, kLaserX, kLaserY, kLaserTheta };
inline constexpr ParamInfo kLaserParams[kNumLaserParams] = {
    {"r_l", "m", false, 1000.0, "mm"},      {"r_r", "m", false, 1000.0, "mm"},
    {"b", "m", false, 1000.0, "mm"},        {"sensor_x", "m", false, 1000.0, "mm"},
    {"sensor_y", "m", false, 1000.0, "mm"}, {"sensor_theta", "rad", true, 180.0 / M_PI, "deg"}};
using LaserParamVector = Eigen::Matrix<double, kNumLaserParams, 1>;
using LaserParamMatrix = Eigen::Matrix<double, kNumLaserParams, kNumLaserParams>;

struct LaserCalibration {
  OdometryParams odometry;
  Pose2d base_T_sensor = Pose2d::Zero();

  LaserParamVector ToVector() const {
    LaserParamVector v;
    v << odometry.left_radius_m, odometry.right_radius_m, odometry.wheelbase_m, base_T_sensor(0),
        base_T_sensor(1), base_T_sensor(2);
    return v;
  }
  static LaserCalibration FromVector(const LaserParamVector& v) {
    LaserCalibration c;
    c.odometry = OdometryParams{v(0), v(1), v(2)};
    c.base_T_sensor = Pose2d(v(3), v(4), v(5));
    return c;
  }
};

}  // namespace calib

#endif  // CALIB_CORE_LASER_LASER_PARAMS_H_
