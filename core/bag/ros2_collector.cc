#include <calib/core/bag/cdr_decoder.h>
#include <calib/core/bag/encoder_messages.h>
#include <calib/core/bag/ros2_collector.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace calib::ros2 {
namespace {

template <typename T>
std::vector<T> InLogTimeOrder(std::vector<std::pair<uint64_t, T>>* logged) {
  std::stable_sort(logged->begin(), logged->end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : a.second.record < b.second.record;
  });
  std::vector<T> out;
  out.reserve(logged->size());
  for (auto& item : *logged) out.push_back(std::move(item.second));
  return out;
}

double Seconds(uint64_t ns) {
  return static_cast<double>(ns / 1000000000) + 1e-9 * static_cast<double>(ns % 1000000000);
}

template <typename Message>
void AppendTopics(std::map<std::string, std::vector<Message>>&& part, int64_t record_base,
                  std::map<std::string, std::vector<Message>>* all) {
  for (auto& [topic, messages] : part) {
    std::vector<Message>& to = (*all)[topic];
    for (Message& m : messages) {
      m.record += record_base;
      to.push_back(std::move(m));
    }
    std::stable_sort(to.begin(), to.end(), [](const Message& a, const Message& b) {
      return a.log_time_s < b.log_time_s;
    });
  }
}

int64_t LastRecord(const RobotMessages& m) {
  int64_t last = -1;
  const auto scan = [&](const auto& topics) {
    for (const auto& [topic, messages] : topics) {
      for (const auto& message : messages) last = std::max<int64_t>(last, message.record);
    }
  };
  scan(m.scans);
  scan(m.joint_states);
  scan(m.odometry);
  for (const auto& [topic, raw] : m.raw) {
    for (const RawMessage& message : raw.messages) last = std::max(last, message.record);
  }
  for (const auto* list : {&m.tf, &m.tf_static}) {
    for (const TransformStamped& t : *list) last = std::max<int64_t>(last, t.record);
  }
  return last;
}

}  // namespace

std::string NormalisedType(const std::string& name) {
  const size_t slash = name.find("/msg/");
  return slash == std::string::npos ? name : name.substr(0, slash) + name.substr(slash + 4);
}

Kind KindOf(const std::string& topic, const std::string& type, const std::string& encoding) {
  if (encoding != "cdr") return Kind::kNone;
  if (type == "sensor_msgs/LaserScan") return Kind::kScan;
  if (type == "sensor_msgs/JointState") return Kind::kJoints;
  if (type == "nav_msgs/Odometry") return Kind::kOdometry;
  if (type != "tf2_msgs/TFMessage") return Kind::kNone;
  const std::string last = topic.substr(topic.rfind('/') + 1);  // npos + 1 == 0.
  return last == "tf" ? Kind::kTf : last == "tf_static" ? Kind::kTfStatic : Kind::kNone;
}

Channel MakeChannel(const std::string& topic, const std::string& type, const std::string& encoding,
                    const BagReadOptions& options, const std::string& definition) {
  Channel channel;
  channel.topic = topic;
  channel.type = NormalisedType(type);
  channel.kind = KindOf(topic, channel.type, encoding);
  const bool raw =
      FindEncoderMessageType(channel.type) != nullptr || options.raw_topics.count(topic) > 0;
  if (channel.kind == Kind::kNone && raw && (encoding == "cdr" || encoding == "ros1")) {
    channel.kind = Kind::kRaw;
    channel.cdr = encoding == "cdr";
    channel.definition = definition;
  }
  channel.wanted =
      channel.kind != Kind::kNone && (options.topics.empty() || options.topics.count(topic) > 0);
  return channel;
}

Status MessageCollector::Decode(const Channel& channel, uint64_t ns, const uint8_t* data,
                                uint64_t size, int64_t record) {
  const double log_time_s = Seconds(ns);
  switch (channel.kind) {
    case Kind::kScan: {
      LaserScan scan;
      CALIB_RETURN_IF_ERROR(DecodeLaserScan(data, size, &scan));
      scan.record = record;
      scan.log_time_s = log_time_s;
      scans_[channel.topic].emplace_back(ns, std::move(scan));
      return Status::Ok();
    }
    case Kind::kJoints: {
      JointState joints;
      CALIB_RETURN_IF_ERROR(DecodeJointState(data, size, &joints));
      joints.record = record;
      joints.log_time_s = log_time_s;
      joints_[channel.topic].emplace_back(ns, std::move(joints));
      return Status::Ok();
    }
    case Kind::kOdometry: {
      Odometry odometry;
      CALIB_RETURN_IF_ERROR(DecodeOdometry(data, size, &odometry));
      odometry.record = record;
      odometry.log_time_s = log_time_s;
      odometry_[channel.topic].emplace_back(ns, std::move(odometry));
      return Status::Ok();
    }
    case Kind::kTf:
    case Kind::kTfStatic: {
      std::vector<TransformStamped> transforms;
      CALIB_RETURN_IF_ERROR(DecodeTfMessage(data, size, &transforms));
      Logged<TransformStamped>& out = channel.kind == Kind::kTf ? tf_ : tf_static_;
      for (TransformStamped& t : transforms) {
        t.record = record;
        t.log_time_s = log_time_s;
        out.emplace_back(ns, std::move(t));
      }
      return Status::Ok();
    }
    case Kind::kRaw: {
      auto& [topic, logged] = raw_[channel.topic];
      if (logged.empty()) topic = RawTopic{channel.type, channel.definition, channel.cdr, {}};
      logged.emplace_back(ns,
                          RawMessage{log_time_s, record, std::vector<uint8_t>(data, data + size)});
      return Status::Ok();
    }
    case Kind::kNone:
      break;
  }
  return Status::Ok();
}

void MessageCollector::Finish(RobotMessages* out) {
  for (auto& [topic, logged] : scans_) out->scans[topic] = InLogTimeOrder(&logged);
  for (auto& [topic, logged] : joints_) out->joint_states[topic] = InLogTimeOrder(&logged);
  for (auto& [topic, logged] : odometry_) out->odometry[topic] = InLogTimeOrder(&logged);
  out->tf = InLogTimeOrder(&tf_);
  out->tf_static = InLogTimeOrder(&tf_static_);
  for (auto& [name, raw] : raw_) {
    RawTopic& topic = out->raw[name] = std::move(raw.first);
    topic.messages = InLogTimeOrder(&raw.second);
  }
}

StatusOr<std::vector<std::string>> BagDirectoryFiles(const std::string& directory,
                                                     const std::string& suffix) {
  std::error_code error;
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(directory, error)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > suffix.size() &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      files.push_back(entry.path().string());
    }
  }
  if (files.empty()) {
    return Status::InvalidInput(directory + ": the bag directory holds no " + suffix + " file");
  }
  // The name without the suffix, split into its text and its trailing count.
  const auto key = [&](const std::string& f) {
    const std::string name = std::filesystem::path(f).filename().string();
    const std::string stem = name.substr(0, name.size() - suffix.size());
    size_t digits = stem.size();
    while (digits > 0 && std::isdigit(static_cast<unsigned char>(stem[digits - 1]))) --digits;
    const std::string number = stem.substr(digits);
    return std::make_pair(stem.substr(0, digits),
                          number.empty() ? -1 : std::stoll(number.substr(0, 18)));
  };
  std::sort(files.begin(), files.end(),
            [&](const std::string& a, const std::string& b) { return key(a) < key(b); });
  return files;
}

int64_t AppendBagPart(RobotMessages&& part, int64_t record_base, RobotMessages* all) {
  int64_t records = 0;
  for (const TopicInfo& t : part.topics) records += t.message_count;
  const int64_t next_base = record_base + std::max(records, LastRecord(part) + 1);
  for (const TopicInfo& t : part.topics) {
    auto it = std::find_if(all->topics.begin(), all->topics.end(),
                           [&](const TopicInfo& a) { return a.name == t.name; });
    if (it == all->topics.end()) {
      all->topics.push_back(t);
    } else {
      it->message_count += t.message_count;
    }
  }
  AppendTopics(std::move(part.scans), record_base, &all->scans);
  AppendTopics(std::move(part.joint_states), record_base, &all->joint_states);
  AppendTopics(std::move(part.odometry), record_base, &all->odometry);
  for (auto& [name, raw] : part.raw) {
    const bool first = all->raw.count(name) == 0;
    RawTopic& to = all->raw[name];
    if (first) to = RawTopic{raw.type, raw.definition, raw.cdr, {}};
    std::map<std::string, std::vector<RawMessage>> appended = {{name, std::move(to.messages)}};
    AppendTopics(std::map<std::string, std::vector<RawMessage>>{{name, std::move(raw.messages)}},
                 record_base, &appended);
    to.messages = std::move(appended[name]);
  }
  for (auto* list : {&part.tf, &part.tf_static}) {
    for (TransformStamped& t : *list) t.record += record_base;
  }
  all->tf.insert(all->tf.end(), part.tf.begin(), part.tf.end());
  all->tf_static.insert(all->tf_static.end(), part.tf_static.begin(), part.tf_static.end());
  return next_base;
}

}  // namespace calib::ros2
