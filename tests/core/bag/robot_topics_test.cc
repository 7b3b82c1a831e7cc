#include <calib/core/bag/robot_topics.h>
#include <gtest/gtest.h>

#include <string>
#include <tuple>
#include <vector>

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

// Real robots' names: TurtleBot3's, Fetch's one-letter sides, a diff-drive with caster joints that
// also say "wheel"; a skid-steer robot's two wheels a side are not guessed.
TEST(RobotTopics, WheelJointsOfRealRobotsArePicked) {
  const std::vector<std::tuple<std::vector<std::string>, std::string, std::string>> cases = {
      {{"wheel_left_joint", "wheel_right_joint"}, "wheel_left_joint", "wheel_right_joint"},
      {{"l_wheel_joint", "r_wheel_joint", "torso_lift_joint"}, "l_wheel_joint", "r_wheel_joint"},
      {{"LeftWheel", "RightWheel"}, "LeftWheel", "RightWheel"},
      {{"left_wheel_joint", "right_wheel_joint", "caster_left_wheel_joint",
        "castor_right_wheel_joint"},
       "left_wheel_joint",
       "right_wheel_joint"},
      {{"front_left_wheel", "rear_left_wheel", "front_right_wheel", "rear_right_wheel"}, "", ""}};
  for (const auto& [names, left, right] : cases) {
    RobotMessages bag = Bag();
    bag.joint_states["/joint_states"] = {Joints(names)};
    const StatusOr<PickedTopics> p = PickRobotTopics(bag, {});
    ASSERT_TRUE(p.ok()) << p.message();
    EXPECT_EQ(p->left_joint, left) << names.front();
    EXPECT_EQ(p->right_joint, right) << names.front();
    EXPECT_EQ(p->odom_topic.empty(), !left.empty()) << names.front();  // Else Odometry's wheels.
  }
}

// No JointState names the wheels but a known encoder message is there: its counts are picked
// before the driver's odometry; an unknown type needs its fields named; a named topic that is
// not in the bag is listed against every topic.
TEST(RobotTopics, AKnownEncoderMessageGivesTheWheels) {
  RobotMessages bag = Bag();
  bag.joint_states["/joint_states"] = {Joints({"arm_joint"})};
  bag.raw["/sensor_state"] = RawTopic{"turtlebot3_msgs/SensorState", "", true, {RawMessage{}}};
  StatusOr<PickedTopics> p = PickRobotTopics(bag, {});
  ASSERT_TRUE(p.ok()) << p.message();
  EXPECT_EQ(p->encoder_topic, "/sensor_state");
  EXPECT_EQ(p->left_encoder_field, "left_encoder");
  EXPECT_EQ(p->right_encoder_field, "right_encoder");
  EXPECT_TRUE(p->odom_topic.empty());

  bag.raw["/ticks"] = RawTopic{"my_robot/Ticks", "int32 l\nint32 r\n", true, {RawMessage{}}};
  TopicChoice choice;
  choice.encoder_topic = "/ticks";
  p = PickRobotTopics(bag, choice);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.message().find("--left_encoder_field"), std::string::npos) << p.message();
  choice.left_encoder_field = "l";
  choice.right_encoder_field = "r";
  p = PickRobotTopics(bag, choice);
  ASSERT_TRUE(p.ok()) << p.message();
  EXPECT_EQ(p->encoder_topic, "/ticks");
  EXPECT_EQ(p->left_encoder_field, "l");
  choice.encoder_topic = "/wheel_ticks";
  p = PickRobotTopics(bag, choice);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.message().find("no topic '/wheel_ticks'"), std::string::npos) << p.message();
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
