#include <calib/core/bag/robot_bag.h>
#include <calib/core/scan/scan_directory.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/laser_input.h>
#include <calib/tools/commands/robot_input.h>

namespace calib::cli {

bool IsRobotInput(const std::string& input) {
  return LooksLikeRobotBag(input) || IsScanDirectory(input);
}

StatusOr<RobotInput> ReadRobotInput(const CalibrateOptions& flags) {
  if (flags.timing == "off") {
    return Status::InvalidInput(flags.input +
                                ": a bag is calibrated with its timing; --timing off applies to "
                                "logs of intervals and stream directories");
  }
  RobotInput out;
  RobotBagOptions& o = out.options;
  o.topics.scan_topic = flags.scan_topic;
  o.topics.joint_state_topic = flags.joint_state_topic;
  o.topics.odom_topic = flags.odom_topic;
  o.topics.left_wheel_joint = flags.left_wheel_joint;
  o.topics.right_wheel_joint = flags.right_wheel_joint;
  o.base_frame = flags.base_frame;
  o.nominal_wheel_radius_m = flags.nominal_wheel_radius;
  o.nominal_wheelbase_m = flags.nominal_wheelbase;
  if (flags.scan_points) o.scan_points = ScanPointOptions();
  o.sensor_time_offset_s = flags.time_offset_s.value_or(0.0);
  CALIB_ASSIGN_OR_RETURN(o.wheel_radians_per_unit, WheelRadiansPerUnit(flags));
  CALIB_ASSIGN_OR_RETURN(out.bag, IsScanDirectory(flags.input) ? ReadScanDirectory(flags.input)
                                                               : ReadRobotBag(flags.input));
  return out;
}

}  // namespace calib::cli
