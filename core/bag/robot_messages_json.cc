#include <calib/core/bag/robot_messages_json.h>
#include <calib/core/text_file.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

namespace calib {
namespace {

using nlohmann::json;

json Number(double value) {
  if (std::isfinite(value)) return value;
  if (std::isnan(value)) return "nan";
  return value > 0 ? "inf" : "-inf";
}

json Numbers(const std::vector<double>& values) {
  json out = json::array();
  for (const double v : values) out.push_back(Number(v));
  return out;
}

json Floats(const std::vector<float>& values) {
  json out = json::array();
  for (const float v : values) out.push_back(Number(v));
  return out;
}

// Nanoseconds since the epoch, clamped to int64; non-finite times become 0.
int64_t Nanoseconds(double t_s) {
  if (!std::isfinite(t_s)) return 0;
  return static_cast<int64_t>(std::llround(std::clamp(t_s, -9.2e9, 9.2e9) * 1e9));
}

json Header(double stamp_s, const std::string& frame_id) {
  const int64_t ns = Nanoseconds(stamp_s);
  const int64_t sec = ns >= 0 ? ns / 1000000000 : -((-ns + 999999999) / 1000000000);
  return {{"stamp", {{"sec", sec}, {"nanosec", ns - sec * 1000000000}}}, {"frame_id", frame_id}};
}

json Vector(const Eigen::Vector3d& v) {
  return {{"x", Number(v.x())}, {"y", Number(v.y())}, {"z", Number(v.z())}};
}

json Quaternion(const Eigen::Quaterniond& q) {
  return {{"x", Number(q.x())}, {"y", Number(q.y())}, {"z", Number(q.z())}, {"w", Number(q.w())}};
}

json ScanMessage(const LaserScan& scan) {
  const int n = static_cast<int>(scan.ranges_m.size());
  return {{"header", Header(scan.stamp_s, scan.frame_id)},
          {"angle_min", Number(scan.angle_min_rad)},
          {"angle_max", Number(scan.BeamAngle(std::max(n - 1, 0)))},
          {"angle_increment", Number(scan.angle_increment_rad)},
          {"time_increment", Number(scan.time_increment_s)},
          {"scan_time", Number(scan.scan_time_s)},
          {"range_min", Number(scan.range_min_m)},
          {"range_max", Number(scan.range_max_m)},
          {"ranges", Floats(scan.ranges_m)},
          {"intensities", Floats(scan.intensities)}};
}

json JointMessage(const JointState& joint) {
  return {{"header", Header(joint.stamp_s, joint.frame_id)},
          {"name", joint.name},
          {"position", Numbers(joint.position)},
          {"velocity", Numbers(joint.velocity)},
          {"effort", Numbers(joint.effort)}};
}

json OdometryMessage(const Odometry& odometry) {
  const json zeros = json(std::vector<double>(36, 0.0));
  return {{"header", Header(odometry.stamp_s, odometry.frame_id)},
          {"child_frame_id", odometry.child_frame_id},
          {"pose",
           {{"pose",
             {{"position", Vector(odometry.position)},
              {"orientation", Quaternion(odometry.orientation)}}},
            {"covariance", zeros}}},
          {"twist",
           {{"twist",
             {{"linear", Vector(odometry.linear_velocity)},
              {"angular", Vector(odometry.angular_velocity)}}},
            {"covariance", zeros}}}};
}

json TransformMessage(const TransformStamped& tf) {
  return {{"header", Header(tf.stamp_s, tf.parent_frame)},
          {"child_frame_id", tf.child_frame},
          {"transform",
           {{"translation", Vector(tf.translation)}, {"rotation", Quaternion(tf.rotation)}}}};
}

struct Entry {
  int64_t log_time_ns;
  json message;  // {"topic", "log_time_ns", "msg"}
};

void Add(const std::string& topic, double log_time_s, json msg, std::vector<Entry>* entries) {
  const int64_t ns = Nanoseconds(log_time_s);
  entries->push_back({ns, json{{"topic", topic}, {"log_time_ns", ns}, {"msg", std::move(msg)}}});
}

void AddTransforms(const std::string& topic, const std::vector<TransformStamped>& transforms,
                   std::vector<Entry>* entries) {
  for (size_t i = 0; i < transforms.size();) {
    json list = json::array();
    const double log_time_s = transforms[i].log_time_s;
    for (; i < transforms.size() && transforms[i].log_time_s == log_time_s; ++i) {
      list.push_back(TransformMessage(transforms[i]));
    }
    Add(topic, log_time_s, json{{"transforms", std::move(list)}}, entries);
  }
}

}  // namespace

std::string RobotMessagesJson(const RobotMessages& messages) {
  json topics = json::array();
  std::vector<Entry> entries;
  for (const auto& [topic, scans] : messages.scans) {
    topics.push_back({{"name", topic}, {"type", "sensor_msgs/LaserScan"}});
    for (const LaserScan& scan : scans) Add(topic, scan.log_time_s, ScanMessage(scan), &entries);
  }
  for (const auto& [topic, joints] : messages.joint_states) {
    topics.push_back({{"name", topic}, {"type", "sensor_msgs/JointState"}});
    for (const JointState& j : joints) Add(topic, j.log_time_s, JointMessage(j), &entries);
  }
  for (const auto& [topic, odometry] : messages.odometry) {
    topics.push_back({{"name", topic}, {"type", "nav_msgs/Odometry"}});
    for (const Odometry& o : odometry) Add(topic, o.log_time_s, OdometryMessage(o), &entries);
  }
  if (!messages.tf.empty()) {
    topics.push_back({{"name", "/tf"}, {"type", "tf2_msgs/TFMessage"}});
    AddTransforms("/tf", messages.tf, &entries);
  }
  if (!messages.tf_static.empty()) {
    topics.push_back({{"name", "/tf_static"}, {"type", "tf2_msgs/TFMessage"}});
    AddTransforms("/tf_static", messages.tf_static, &entries);
  }
  std::stable_sort(entries.begin(), entries.end(),
                   [](const Entry& a, const Entry& b) { return a.log_time_ns < b.log_time_ns; });
  json list = json::array();
  for (Entry& entry : entries) list.push_back(std::move(entry.message));
  const json out = {{"topics", std::move(topics)}, {"messages", std::move(list)}};
  return out.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
}

Status WriteRobotMessagesJson(const RobotMessages& messages, const std::string& path) {
  return WriteWholeFile(path, RobotMessagesJson(messages));
}

}  // namespace calib
