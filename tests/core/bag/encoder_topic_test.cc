#include <calib/core/bag/robot_bag.h>
#include <calib/core/bag/wheel_angles.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace calib {
namespace {

const std::string kBags = std::string(CALIB_SOURCE_DIR) + "/data/bags/";
constexpr double kTwoPi = 6.283185307179586;

// The simulated robot's recording with its wheels as raw encoder counts in the robot's own
// message (scripts/fixtures/joints_to_ticks.py): TurtleBot3's int32 counts (4096 a turn) in an
// MCAP and a ROS 1 bag; Kobuki's uint16 counts (2578.33 a turn) that wrap, in rosbag2's sqlite3
// storage with (Jazzy) and without (Humble) the message definitions.
struct TickBag {
  std::string path, topic;
  double ticks_per_turn;
  bool definition_stored;
};
const std::vector<TickBag> kTickBags = {
    {"sim_turtlebot_ticks_zstd.mcap", "/sensor_state", 4096.0, true},
    {"sim_turtlebot_ticks_lz4.bag", "/sensor_state", 4096.0, true},
    {"sim_kobuki_ticks_db3", "/mobile_base/sensors/core", 2578.333869740464, true},
    {"sim_kobuki_ticks_humble_db3", "/mobile_base/sensors/core", 2578.333869740464, false},
};

// Every bag's counts, unwrapped and scaled, follow the wheel joints of the same recording
// (sim_robot_zstd.mcap) to within a count; their stamps are the joints' stamps.
TEST(EncoderTopic, CountsFollowTheWheelJointsInEveryFormat) {
  const auto joints_bag = ReadRobotBag(kBags + "sim_robot_zstd.mcap");
  ASSERT_TRUE(joints_bag.ok()) << joints_bag.message();
  const auto joints = WheelAnglesFromJointStates(joints_bag->joint_states.at("/joint_states"),
                                                 "left_wheel_joint", "right_wheel_joint", "sim");
  ASSERT_TRUE(joints.ok()) << joints.message();
  for (const TickBag& tick_bag : kTickBags) {
    SCOPED_TRACE(tick_bag.path);
    const auto bag = ReadRobotBag(kBags + tick_bag.path);
    ASSERT_TRUE(bag.ok()) << bag.message();
    ASSERT_EQ(1u, bag->raw.count(tick_bag.topic));
    const RawTopic& topic = bag->raw.at(tick_bag.topic);
    EXPECT_EQ(tick_bag.definition_stored, !topic.definition.empty());
    const auto ticks = WheelAnglesFromEncoderTopic(topic, "left_encoder", "right_encoder",
                                                   tick_bag.path, kTwoPi / tick_bag.ticks_per_turn);
    ASSERT_TRUE(ticks.ok()) << ticks.message();
    ASSERT_EQ(joints->samples.size(), ticks->samples.size());
    const double count = kTwoPi / tick_bag.ticks_per_turn;
    const EncoderSample& j0 = joints->samples.front();
    const EncoderSample& t0 = ticks->samples.front();
    for (size_t k = 0; k < ticks->samples.size(); ++k) {
      const EncoderSample& j = joints->samples[k];
      const EncoderSample& t = ticks->samples[k];
      EXPECT_EQ(j.t_s, t.t_s);
      EXPECT_NEAR(t.left_rad - t0.left_rad, j.left_rad - j0.left_rad, 1.01 * count) << k;
      EXPECT_NEAR(t.right_rad - t0.right_rad, j.right_rad - j0.right_rad, 1.01 * count) << k;
    }
    EXPECT_EQ(tick_bag.ticks_per_turn<4000.0, ticks->counter_wraps> 0);  // Kobuki's wrap.
  }
}

// A field that is not there, or not a number, is named with the fields there are.
TEST(EncoderTopic, AWrongFieldIsNamed) {
  const auto bag = ReadRobotBag(kBags + "sim_turtlebot_ticks_zstd.mcap");
  ASSERT_TRUE(bag.ok()) << bag.message();
  const RawTopic& topic = bag->raw.at("/sensor_state");
  auto ticks = WheelAnglesFromEncoderTopic(topic, "left_ticks", "right_encoder", "run.mcap /s", 1);
  ASSERT_FALSE(ticks.ok());
  EXPECT_NE(ticks.message().find("run.mcap /s: "), std::string::npos) << ticks.message();
  EXPECT_NE(ticks.message().find("left_ticks"), std::string::npos) << ticks.message();
  EXPECT_NE(ticks.message().find("left_encoder"), std::string::npos) << ticks.message();
  ticks = WheelAnglesFromEncoderTopic(topic, "header.frame_id", "right_encoder", "run.mcap /s", 1);
  ASSERT_FALSE(ticks.ok());
  RawTopic unknown = topic;
  unknown.type = "my_robot/Ticks";
  unknown.definition.clear();
  ticks = WheelAnglesFromEncoderTopic(unknown, "left_encoder", "right_encoder", "run.db3 /s", 1);
  ASSERT_FALSE(ticks.ok());
  EXPECT_NE(ticks.message().find("stores no definition of my_robot/Ticks"), std::string::npos)
      << ticks.message();
  RawTopic cut = topic;
  cut.messages[3].data.resize(20);
  ticks = WheelAnglesFromEncoderTopic(cut, "left_encoder", "right_encoder", "run.mcap /s", 1);
  ASSERT_FALSE(ticks.ok());
  EXPECT_NE(ticks.message().find("record " + std::to_string(cut.messages[3].record)),
            std::string::npos)
      << ticks.message();
}

}  // namespace
}  // namespace calib
