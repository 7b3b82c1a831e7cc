#ifndef CALIB_CORE_BAG_ROS1_DECODER_H_
#define CALIB_CORE_BAG_ROS1_DECODER_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/core/status.h>

#include <string_view>
#include <vector>

// Decoders of the ROS 1 serialization of the messages a calibration reads: little-endian, no
// alignment, strings as u32 length + bytes, variable arrays as u32 count + elements, fixed arrays
// without a count, time as u32 secs + u32 nsecs, std_msgs/Header as seq u32, stamp, frame_id.
// Each fills the message's fields but leaves log_time_s and record to the caller. A message
// shorter than its fields, or longer, fails with a message naming the field and byte.
namespace calib::ros1 {

Status DecodeLaserScan(std::string_view bytes, LaserScan* scan);
Status DecodeJointState(std::string_view bytes, JointState* joints);
Status DecodeOdometry(std::string_view bytes, Odometry* odometry);
// tf2_msgs/TFMessage: appends its transforms.
Status DecodeTfMessage(std::string_view bytes, std::vector<TransformStamped>* transforms);

}  // namespace calib::ros1

#endif  // CALIB_CORE_BAG_ROS1_DECODER_H_
