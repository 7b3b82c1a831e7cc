#ifndef CALIB_TESTS_CORE_BAG_SMALL_ROBOT_EXPECTATIONS_H_
#define CALIB_TESTS_CORE_BAG_SMALL_ROBOT_EXPECTATIONS_H_

// Checks of a ROS 2 bag's decoded messages against data/bags/small_robot.json, the input its
// reference writer was given (write_mcap.mjs, write_db3.mjs): every field, record and log time.
#include <calib/core/bag/robot_messages.h>
#include <calib/core/text_file.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace calib::testing {

inline const std::string kBags = std::string(CALIB_SOURCE_DIR) + "/data/bags/";

inline nlohmann::json Input() {
  std::string text;
  EXPECT_TRUE(ReadWholeFile(kBags + "small_robot.json", &text).ok());
  return nlohmann::json::parse(text);
}

inline double Seconds(uint64_t ns) {
  return static_cast<double>(ns / 1000000000) + 1e-9 * static_cast<double>(ns % 1000000000);
}
inline double Stamp(const nlohmann::json& header) {
  return header["stamp"]["sec"].get<int32_t>() + 1e-9 * header["stamp"]["nanosec"].get<uint32_t>();
}
inline float Float(const nlohmann::json& v) {
  if (v.is_string()) {
    const std::string s = v.get<std::string>();
    return s == "nan" ? NAN : s == "inf" ? INFINITY : -INFINITY;
  }
  return static_cast<float>(v.get<double>());
}
inline void ExpectSameFloat(float expected, float actual, const std::string& what) {
  if (std::isnan(expected)) {
    EXPECT_TRUE(std::isnan(actual)) << what;
  } else {
    EXPECT_EQ(expected, actual) << what;
  }
}
inline Eigen::Vector3d Vec(const nlohmann::json& v) {
  return {v["x"].get<double>(), v["y"].get<double>(), v["z"].get<double>()};
}
inline void ExpectQuaternion(const nlohmann::json& q, const Eigen::Quaterniond& actual) {
  EXPECT_EQ(q["x"].get<double>(), actual.x());
  EXPECT_EQ(q["y"].get<double>(), actual.y());
  EXPECT_EQ(q["z"].get<double>(), actual.z());
  EXPECT_EQ(q["w"].get<double>(), actual.w());
}

// The JSON's messages of one topic with their record numbers, in (log time, record) order.
inline std::vector<std::pair<int64_t, nlohmann::json>> Expected(const nlohmann::json& input,
                                                                const std::string& topic) {
  std::vector<std::pair<int64_t, nlohmann::json>> out;
  const auto& messages = input["messages"];
  for (size_t i = 0; i < messages.size(); ++i) {
    if (messages[i]["topic"] == topic) out.emplace_back(i, messages[i]);
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.second["log_time_ns"].template get<uint64_t>() <
           b.second["log_time_ns"].template get<uint64_t>();
  });
  return out;
}

inline void ExpectScans(const nlohmann::json& input, const std::vector<LaserScan>& scans) {
  const auto expected = Expected(input, "/scan");
  ASSERT_EQ(expected.size(), scans.size());
  for (size_t k = 0; k < scans.size(); ++k) {
    const LaserScan& s = scans[k];
    const nlohmann::json& m = expected[k].second["msg"];
    EXPECT_EQ(expected[k].first, s.record);
    EXPECT_EQ(Seconds(expected[k].second["log_time_ns"].get<uint64_t>()), s.log_time_s);
    EXPECT_EQ(Stamp(m["header"]), s.stamp_s);
    EXPECT_EQ(m["header"]["frame_id"], s.frame_id);
    EXPECT_EQ(Float(m["angle_min"]), s.angle_min_rad);
    EXPECT_EQ(Float(m["angle_increment"]), s.angle_increment_rad);
    EXPECT_EQ(Float(m["time_increment"]), s.time_increment_s);
    EXPECT_EQ(Float(m["scan_time"]), s.scan_time_s);
    EXPECT_EQ(Float(m["range_min"]), s.range_min_m);
    EXPECT_EQ(Float(m["range_max"]), s.range_max_m);
    ASSERT_EQ(m["ranges"].size(), s.ranges_m.size());
    ASSERT_EQ(m["intensities"].size(), s.intensities.size());
    for (size_t i = 0; i < s.ranges_m.size(); ++i) {
      ExpectSameFloat(Float(m["ranges"][i]), s.ranges_m[i], "scan " + std::to_string(k));
    }
    for (size_t i = 0; i < s.intensities.size(); ++i) {
      EXPECT_EQ(Float(m["intensities"][i]), s.intensities[i]);
    }
  }
}

inline void ExpectJoints(const nlohmann::json& input, const std::vector<JointState>& joints) {
  const auto expected = Expected(input, "/joint_states");
  ASSERT_EQ(expected.size(), joints.size());
  for (size_t k = 0; k < joints.size(); ++k) {
    const nlohmann::json& m = expected[k].second["msg"];
    EXPECT_EQ(expected[k].first, joints[k].record);
    EXPECT_EQ(Seconds(expected[k].second["log_time_ns"].get<uint64_t>()), joints[k].log_time_s);
    EXPECT_EQ(Stamp(m["header"]), joints[k].stamp_s);
    EXPECT_EQ(m["name"].get<std::vector<std::string>>(), joints[k].name);
    EXPECT_EQ(m["position"].get<std::vector<double>>(), joints[k].position);
    EXPECT_EQ(m["velocity"].get<std::vector<double>>(), joints[k].velocity);
    EXPECT_EQ(m["effort"].get<std::vector<double>>(), joints[k].effort);
  }
}

inline void ExpectOdometry(const nlohmann::json& input, const std::vector<Odometry>& odometry) {
  const auto expected = Expected(input, "/odom");
  ASSERT_EQ(expected.size(), odometry.size());
  for (size_t k = 0; k < odometry.size(); ++k) {
    const nlohmann::json& m = expected[k].second["msg"];
    const Odometry& o = odometry[k];
    EXPECT_EQ(expected[k].first, o.record);
    EXPECT_EQ(Seconds(expected[k].second["log_time_ns"].get<uint64_t>()), o.log_time_s);
    EXPECT_EQ(Stamp(m["header"]), o.stamp_s);
    EXPECT_EQ(m["header"]["frame_id"], o.frame_id);
    EXPECT_EQ(m["child_frame_id"], o.child_frame_id);
    EXPECT_EQ(Vec(m["pose"]["pose"]["position"]), o.position);
    ExpectQuaternion(m["pose"]["pose"]["orientation"], o.orientation);
    EXPECT_EQ(Vec(m["twist"]["twist"]["linear"]), o.linear_velocity);
    EXPECT_EQ(Vec(m["twist"]["twist"]["angular"]), o.angular_velocity);
  }
}

inline void ExpectTransforms(const nlohmann::json& input, const std::string& topic,
                             const std::vector<TransformStamped>& transforms) {
  size_t j = 0;
  for (const auto& [record, message] : Expected(input, topic)) {
    for (const nlohmann::json& t : message["msg"]["transforms"]) {
      ASSERT_LT(j, transforms.size());
      const TransformStamped& a = transforms[j++];
      EXPECT_EQ(record, a.record);
      EXPECT_EQ(Seconds(message["log_time_ns"].get<uint64_t>()), a.log_time_s);
      EXPECT_EQ(Stamp(t["header"]), a.stamp_s);
      EXPECT_EQ(t["header"]["frame_id"], a.parent_frame);
      EXPECT_EQ(t["child_frame_id"], a.child_frame);
      EXPECT_EQ(Vec(t["transform"]["translation"]), a.translation);
      ExpectQuaternion(t["transform"]["rotation"], a.rotation);
    }
  }
  EXPECT_EQ(j, transforms.size());
}

// Every message of small_robot.json, decoded from `bag` (read from `source`).
inline void ExpectSmallRobot(const RobotMessages& bag) {
  const nlohmann::json input = Input();
  ASSERT_EQ(1u, bag.scans.size());
  ASSERT_EQ(1u, bag.joint_states.size());
  ASSERT_EQ(1u, bag.odometry.size());
  ExpectScans(input, bag.scans.at("/scan"));
  ExpectJoints(input, bag.joint_states.at("/joint_states"));
  ExpectOdometry(input, bag.odometry.at("/odom"));
  ExpectTransforms(input, "/tf", bag.tf);
  ExpectTransforms(input, "/tf_static", bag.tf_static);
  EXPECT_EQ(8u, bag.tf.size());
  ASSERT_EQ(1u, bag.tf_static.size());
  EXPECT_EQ("base_link", bag.tf_static[0].parent_frame);
  EXPECT_EQ("laser", bag.tf_static[0].child_frame);
}

// small_robot.json's topics, in its order, with their types and counts.
inline void ExpectSmallRobotTopics(const RobotMessages& bag) {
  const std::vector<std::tuple<std::string, std::string, int64_t>> expected = {
      {"/scan", "sensor_msgs/LaserScan", 20},
      {"/joint_states", "sensor_msgs/JointState", 40},
      {"/odom", "nav_msgs/Odometry", 40},
      {"/tf", "tf2_msgs/TFMessage", 4},
      {"/tf_static", "tf2_msgs/TFMessage", 1}};
  ASSERT_EQ(expected.size(), bag.topics.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(std::get<0>(expected[i]), bag.topics[i].name);
    EXPECT_EQ(std::get<1>(expected[i]), bag.topics[i].type);
    EXPECT_EQ(std::get<2>(expected[i]), bag.topics[i].message_count);
  }
}

}  // namespace calib::testing

#endif  // CALIB_TESTS_CORE_BAG_SMALL_ROBOT_EXPECTATIONS_H_
