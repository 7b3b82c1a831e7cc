#include <calib/core/bag/robot_topics.h>
#include <gtest/gtest.h>

namespace calib {
namespace {

JointState Joints(std::vector<std::string> names) {
  JointState j;
  j.name = std::move(names);
  j.position.assign(j.name.size(), 0.0);
  return j;
}

RobotMessages Bag() {
  RobotMessages bag;
  bag.source = "run.mcap";
  bag.topics = {{"/scan", "sensor_msgs/LaserScan", 2},
                {"/joint_states", "sensor_msgs/JointState", 2},
                {"/odom", "nav_msgs/Odometry", 1}};
  bag.scans["/scan"].resize(2);
  bag.joint_states["/joint_states"] = {Joints({"arm_joint"}),
                                       Joints({"wheel_left_joint", "wheel_right_joint"})};
  bag.odometry["/odom"].resize(1);
  return bag;
}

TEST(RobotTopics, UniqueTopicsAndWheelJointsArePicked) {
  const StatusOr<PickedTopics> p = PickRobotTopics(Bag(), {});
  ASSERT_TRUE(p.ok()) << p.message();
  EXPECT_EQ(p->scan_topic, "/scan");
  EXPECT_EQ(p->joint_state_topic, "/joint_states");
  EXPECT_EQ(p->left_joint, "wheel_left_joint");
  EXPECT_EQ(p->right_joint, "wheel_right_joint");
  EXPECT_TRUE(p->odom_topic.empty());
}

TEST(RobotTopics, SeveralScanTopicsAreListedWithTheFlag) {
  RobotMessages bag = Bag();
  bag.topics.push_back({"/scan_rear", "sensor_msgs/LaserScan", 3});
  bag.scans["/scan_rear"].resize(3);
  const StatusOr<PickedTopics> p = PickRobotTopics(bag, {});
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.message().find("/scan (sensor_msgs/LaserScan, 2 messages)"), std::string::npos);
  EXPECT_NE(p.message().find("/scan_rear (sensor_msgs/LaserScan, 3 messages)"), std::string::npos);
  EXPECT_NE(p.message().find("--scan_topic"), std::string::npos);
  TopicChoice choice;
  choice.scan_topic = "/scan_rear";
  EXPECT_EQ(PickRobotTopics(bag, choice)->scan_topic, "/scan_rear");
}

TEST(RobotTopics, AMissingTopicOrJointIsNamed) {
  TopicChoice choice;
  choice.scan_topic = "/laser";
  StatusOr<PickedTopics> p = PickRobotTopics(Bag(), choice);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.message().find("'/laser'"), std::string::npos);
  choice = {};
  choice.left_wheel_joint = "left";
  choice.right_wheel_joint = "right";
  p = PickRobotTopics(Bag(), choice);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.message().find("wheel_left_joint"), std::string::npos) << p.message();
}

TEST(RobotTopics, OdometryWhenNoJointStateNamesTheWheels) {
  RobotMessages bag = Bag();
  bag.joint_states["/joint_states"] = {Joints({"arm_joint"})};
  const StatusOr<PickedTopics> p = PickRobotTopics(bag, {});
  ASSERT_TRUE(p.ok()) << p.message();
  EXPECT_TRUE(p->joint_state_topic.empty());
  EXPECT_EQ(p->odom_topic, "/odom");
  bag.odometry.clear();
  const StatusOr<PickedTopics> none = PickRobotTopics(bag, {});
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.message().find("arm_joint"), std::string::npos) << none.message();
  EXPECT_NE(none.message().find("--left_wheel_joint"), std::string::npos);
}

}  // namespace
}  // namespace calib
