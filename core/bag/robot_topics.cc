#include <calib/core/bag/encoder_messages.h>
#include <calib/core/bag/robot_topics.h>

#include <algorithm>
#include <cctype>
#include <set>
#include <vector>

namespace calib {
namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// "/scan (sensor_msgs/LaserScan, 1200 messages), ..." for the topics of `type` (all when empty).
std::string Candidates(const RobotMessages& bag, const std::string& type) {
  std::string out;
  for (const TopicInfo& t : bag.topics) {
    if (!type.empty() && t.type != type) continue;
    if (!out.empty()) out += ", ";
    out += t.name + " (" + t.type + ", " + std::to_string(t.message_count) + " messages)";
  }
  return out.empty() ? "none" : out;
}

StatusOr<std::string> PickScanTopic(const RobotMessages& bag, const std::string& wanted) {
  const std::string kType = "sensor_msgs/LaserScan";
  if (!wanted.empty()) {
    if (bag.scans.count(wanted) == 0) {
      return Status::InvalidInput(bag.source + ": no LaserScan topic '" + wanted +
                                  "'; LaserScan topics: " + Candidates(bag, kType) +
                                  "; all topics: " + Candidates(bag, ""));
    }
    return wanted;
  }
  std::vector<std::string> with_messages;
  for (const auto& [topic, scans] : bag.scans) {
    if (!scans.empty()) with_messages.push_back(topic);
  }
  if (with_messages.size() == 1) return with_messages.front();
  if (with_messages.empty()) {
    return Status::InvalidInput(
        bag.source + ": no sensor_msgs/LaserScan messages; topics: " + Candidates(bag, ""));
  }
  return Status::InvalidInput(bag.source + ": several LaserScan topics: " + Candidates(bag, kType) +
                              "; choose one with --scan_topic");
}

// Every joint name the topic's messages carry.
std::set<std::string> JointNames(const std::vector<JointState>& messages) {
  std::set<std::string> names;
  for (const JointState& m : messages) names.insert(m.name.begin(), m.name.end());
  return names;
}

std::string Join(const std::set<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "none" : out;
}

// Whether a joint names a drive wheel on `side` ("left" or "right"): its name (case-insensitive)
// holds "wheel" and the side, spelt out or as the word "l" or "r" (Fetch's l_wheel_joint), and
// names no caster (whose joints also say "wheel" on some robots).
bool SideWheel(const std::string& name, const std::string& side) {
  const std::string l = Lower(name);
  if (l.find("wheel") == std::string::npos || l.find("caster") != std::string::npos ||
      l.find("castor") != std::string::npos) {
    return false;
  }
  if (l.find(side) != std::string::npos) return true;
  for (size_t begin = 0; begin < l.size();) {
    size_t end = begin;
    while (end < l.size() && std::isalnum(static_cast<unsigned char>(l[end]))) ++end;
    if (end - begin == 1 && l[begin] == side[0]) return true;
    begin = end + 1;
  }
  return false;
}

// The joint SideWheel finds on `side`, when exactly one is (a skid-steer robot's two wheels a
// side are for the user to choose).
std::string WheelJoint(const std::set<std::string>& names, const std::string& side) {
  std::string found;
  for (const std::string& n : names) {
    if (!SideWheel(n, side)) continue;
    if (!found.empty()) return "";
    found = n;
  }
  return found;
}

// The JointState topics whose messages carry both joints (named, or found by WheelJoint).
Status PickJoints(const RobotMessages& bag, const TopicChoice& choice, PickedTopics* out) {
  std::vector<PickedTopics> matches;
  std::string seen;
  if (!choice.joint_state_topic.empty() && bag.joint_states.count(choice.joint_state_topic) == 0) {
    return Status::InvalidInput(
        bag.source + ": no JointState topic '" + choice.joint_state_topic +
        "'; JointState topics: " + Candidates(bag, "sensor_msgs/JointState"));
  }
  for (const auto& [topic, messages] : bag.joint_states) {
    if (!choice.joint_state_topic.empty() && topic != choice.joint_state_topic) continue;
    const std::set<std::string> names = JointNames(messages);
    seen += (seen.empty() ? "" : "; ") + topic + ": " + Join(names);
    PickedTopics p;
    p.joint_state_topic = topic;
    p.left_joint =
        choice.left_wheel_joint.empty() ? WheelJoint(names, "left") : choice.left_wheel_joint;
    p.right_joint =
        choice.right_wheel_joint.empty() ? WheelJoint(names, "right") : choice.right_wheel_joint;
    if (names.count(p.left_joint) && names.count(p.right_joint)) matches.push_back(p);
  }
  const bool named = !choice.left_wheel_joint.empty() || !choice.right_wheel_joint.empty() ||
                     !choice.joint_state_topic.empty();
  if (matches.size() == 1) {
    out->joint_state_topic = matches.front().joint_state_topic;
    out->left_joint = matches.front().left_joint;
    out->right_joint = matches.front().right_joint;
    return Status::Ok();
  }
  if (matches.size() > 1) {
    return Status::InvalidInput(bag.source +
                                ": several JointState topics carry the wheel joints (" + seen +
                                "); choose one with --joint_state_topic");
  }
  if (named) {
    const auto shown = [](const std::string& joint, const char* side) {
      return joint.empty() ? std::string("a unique ") + side + " wheel joint" : "'" + joint + "'";
    };
    return Status::InvalidInput(bag.source + ": no JointState topic carries both " +
                                shown(choice.left_wheel_joint, "left") + " and " +
                                shown(choice.right_wheel_joint, "right") +
                                "; joints seen: " + (seen.empty() ? "no JointState topic" : seen) +
                                " (name them with --left_wheel_joint and --right_wheel_joint)");
  }
  return Status::Ok();  // None found: the caller falls back to Odometry.
}

// "/sensor_state (turtlebot3_msgs/SensorState, 2000 messages), ..." for the raw topics.
std::string RawCandidates(const RobotMessages& bag) {
  std::string out;
  for (const auto& [topic, raw] : bag.raw) {
    out += (out.empty() ? "" : ", ") + topic + " (" + raw.type + ", " +
           std::to_string(raw.messages.size()) + " messages)";
  }
  return out.empty() ? "none" : out;
}

// The encoder topic: the one named (then it must be there, and its fields known or named), or
// the only raw topic of a known encoder type (none found: *out unchanged).
Status PickEncoderTopic(const RobotMessages& bag, const TopicChoice& choice, PickedTopics* out) {
  std::string topic = choice.encoder_topic;
  if (topic.empty()) {
    for (const auto& [name, raw] : bag.raw) {
      if (FindEncoderMessageType(raw.type) == nullptr || raw.messages.empty()) continue;
      if (!topic.empty()) {
        return Status::InvalidInput(bag.source +
                                    ": no JointState names the wheels, and several topics carry "
                                    "encoder counts: " +
                                    RawCandidates(bag) + "; choose one with --encoder_topic");
      }
      topic = name;
    }
    if (topic.empty()) return Status::Ok();
  }
  const auto raw = bag.raw.find(topic);
  if (raw == bag.raw.end()) {
    return Status::InvalidInput(
        bag.source + ": no topic '" + topic +
        "' to read encoder counts from; all topics: " + Candidates(bag, ""));
  }
  const EncoderMessageType* known = FindEncoderMessageType(raw->second.type);
  out->encoder_topic = topic;
  out->left_encoder_field = !choice.left_encoder_field.empty() ? choice.left_encoder_field
                            : known != nullptr                 ? known->left_field
                                                               : "";
  out->right_encoder_field = !choice.right_encoder_field.empty() ? choice.right_encoder_field
                             : known != nullptr                  ? known->right_field
                                                                 : "";
  if (out->left_encoder_field.empty() || out->right_encoder_field.empty()) {
    return Status::InvalidInput(bag.source + ": topic '" + topic + "' is of type " +
                                raw->second.type +
                                ", whose encoder fields calib does not know: name them with "
                                "--left_encoder_field and --right_encoder_field");
  }
  return Status::Ok();
}

StatusOr<std::string> PickOdomTopic(const RobotMessages& bag, const std::string& wanted,
                                    const std::string& joints_seen) {
  const std::string kType = "nav_msgs/Odometry";
  if (!wanted.empty()) {
    if (bag.odometry.count(wanted) == 0) {
      return Status::InvalidInput(bag.source + ": no Odometry topic '" + wanted +
                                  "'; Odometry topics: " + Candidates(bag, kType));
    }
    return wanted;
  }
  std::vector<std::string> with_messages;
  for (const auto& [topic, messages] : bag.odometry) {
    if (!messages.empty()) with_messages.push_back(topic);
  }
  if (with_messages.size() == 1) return with_messages.front();
  const std::string why =
      bag.source + ": no JointState topic names two wheel joints (" + joints_seen + ")";
  if (with_messages.empty()) {
    return Status::InvalidInput(why +
                                " and there is no nav_msgs/Odometry topic: name the wheel "
                                "joints with --left_wheel_joint and --right_wheel_joint");
  }
  return Status::InvalidInput(why + " and there are several Odometry topics: " +
                              Candidates(bag, kType) + "; choose one with --odom_topic");
}

}  // namespace

StatusOr<PickedTopics> PickRobotTopics(const RobotMessages& bag, const TopicChoice& choice) {
  PickedTopics out;
  CALIB_ASSIGN_OR_RETURN(out.scan_topic, PickScanTopic(bag, choice.scan_topic));
  if (!choice.encoder_topic.empty()) {
    CALIB_RETURN_IF_ERROR(PickEncoderTopic(bag, choice, &out));
    return out;
  }
  if (choice.odom_topic.empty()) CALIB_RETURN_IF_ERROR(PickJoints(bag, choice, &out));
  if (!out.joint_state_topic.empty()) return out;
  if (choice.odom_topic.empty() && choice.joint_state_topic.empty()) {
    CALIB_RETURN_IF_ERROR(PickEncoderTopic(bag, choice, &out));
    if (!out.encoder_topic.empty()) return out;
  }
  std::string joints_seen;
  for (const auto& [topic, messages] : bag.joint_states) {
    joints_seen += (joints_seen.empty() ? "" : "; ") + topic + ": " + Join(JointNames(messages));
  }
  CALIB_ASSIGN_OR_RETURN(out.odom_topic,
                         PickOdomTopic(bag, choice.odom_topic,
                                       joints_seen.empty() ? "no JointState topic" : joints_seen));
  return out;
}

}  // namespace calib
