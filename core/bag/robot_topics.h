#ifndef CALIB_CORE_BAG_ROBOT_TOPICS_H_
#define CALIB_CORE_BAG_ROBOT_TOPICS_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/status.h>

#include <string>

// Which topics of a robot's bag the laser calibration reads: the scans, and the wheel angles
// from a JointState topic's two wheel joints, or (when no joint state names wheels) from an
// Odometry topic. Picked automatically when the choice is unique; otherwise the error lists the
// candidates with their types and counts and the flag that chooses.
namespace calib {

struct TopicChoice {  // The user's choice; empty fields are picked automatically.
  std::string scan_topic, odom_topic, joint_state_topic;
  std::string left_wheel_joint, right_wheel_joint;
};

struct PickedTopics {
  std::string scan_topic;
  // Wheel angles from these joints of this JointState topic, or, when it is empty, from the
  // poses of odom_topic.
  std::string joint_state_topic, left_joint, right_joint;
  std::string odom_topic;
};

StatusOr<PickedTopics> PickRobotTopics(const RobotMessages& bag, const TopicChoice& choice);

}  // namespace calib

#endif  // CALIB_CORE_BAG_ROBOT_TOPICS_H_
