#ifndef CALIB_CORE_BAG_ROBOT_TOPICS_H_
#define CALIB_CORE_BAG_ROBOT_TOPICS_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/status.h>

#include <string>

// Which topics of a robot's bag the laser calibration reads: the scans, and the wheel angles
// from a JointState topic's two wheel joints, or (when no joint state names wheels) from the
// encoder counts of a robot's own message of a known type (or one named), or from an Odometry
// topic. Picked automatically when the choice is unique; otherwise the error lists the
// candidates with their types and counts and the flag that chooses.
namespace calib {

struct TopicChoice {  // The user's choice; empty fields are picked automatically.
  std::string scan_topic, odom_topic, joint_state_topic;
  std::string left_wheel_joint, right_wheel_joint;
  // A robot's own message with its raw encoder counts (read raw: RobotMessages::raw) and the
  // fields that hold them (empty: a known type's, encoder_messages.h).
  std::string encoder_topic, left_encoder_field, right_encoder_field;
};

struct PickedTopics {
  std::string scan_topic;
  // Wheel angles from these joints of this JointState topic; or from these fields of the raw
  // encoder topic; or, when both are empty, from the poses of odom_topic.
  std::string joint_state_topic, left_joint, right_joint;
  std::string encoder_topic, left_encoder_field, right_encoder_field;
  std::string odom_topic;
};

StatusOr<PickedTopics> PickRobotTopics(const RobotMessages& bag, const TopicChoice& choice);

}  // namespace calib

#endif  // CALIB_CORE_BAG_ROBOT_TOPICS_H_
