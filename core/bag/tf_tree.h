#ifndef CALIB_CORE_BAG_TF_TREE_H_
#define CALIB_CORE_BAG_TF_TREE_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/se2.h>
#include <calib/core/status.h>

#include <Eigen/Geometry>
#include <string>

// A sensor's nominal mounting from a bag's tf: the transforms of /tf_static (and, for a frame
// that only /tf names, its first transform there), chained through intermediate frames from the
// base frame to the sensor's.
namespace calib {

struct PlanarMounting {
  Pose2d base_T_sensor = Pose2d::Zero();  // Projected on the base's plane (x, y, yaw).
  // The sensor's z axis points down (mounted upside down): its scans turn clockwise in the base
  // frame, and a 2D calibration must mirror them.
  bool upside_down = false;
  double tilt_rad = 0.0;  // Between the sensor's z axis and the base's (0 or π when level).
  std::string chain;      // "base_link → laser_mount → laser".
  Eigen::Isometry3d base_T_sensor_3d = Eigen::Isometry3d::Identity();  // As tf gives it.
};

// Frame names compare without a leading '/' (ROS 1 bags often have one).
StatusOr<PlanarMounting> MountingFromTf(const RobotMessages& bag, const std::string& base_frame,
                                        const std::string& sensor_frame);

}  // namespace calib

#endif  // CALIB_CORE_BAG_TF_TREE_H_
