#ifndef CALIB_CORE_BAG_ENCODER_MESSAGES_H_
#define CALIB_CORE_BAG_ENCODER_MESSAGES_H_

#include <string>

// Messages in which robots publish their raw wheel encoder counts, known by type: the bag readers
// keep their topics raw (RobotMessages::raw), and the wheel angles come from their tick fields
// when no JointState names the wheels.
namespace calib {

struct EncoderMessageType {
  const char* type;  // Normalised "package/Type".
  const char* left_field;
  const char* right_field;
  double ticks_per_turn;    // The robot's counts per wheel turn.
  const char* ros2_fields;  // The ROS 2 .msg text (its first field a std_msgs/Header).
  // The ROS 2 definition as a bag stores it (with its dependencies), for bags that store none
  // (rosbag2's sqlite3 storage before Jazzy).
  std::string Ros2Definition() const;
};

// The known type `type` ("package/Type" or "package/msg/Type"), or null.
const EncoderMessageType* FindEncoderMessageType(const std::string& type);

}  // namespace calib

#endif  // CALIB_CORE_BAG_ENCODER_MESSAGES_H_
