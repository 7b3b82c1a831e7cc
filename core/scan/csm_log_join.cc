#include <calib/core/scan/csm_log.h>

#include <algorithm>
#include <filesystem>
#include <iterator>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace calib {
namespace {

// A log's recording moved by dt_s in time, its counts by `counts`, its records by `records`.
void Shift(double dt_s, const std::vector<double>& counts, int64_t records, RobotMessages* bag) {
  for (auto& [topic, scans] : bag->scans) {
    for (LaserScan& s : scans) s.stamp_s += dt_s, s.log_time_s += dt_s, s.record += records;
  }
  for (auto& [topic, joints] : bag->joint_states) {
    for (JointState& j : joints) {
      j.stamp_s += dt_s, j.log_time_s += dt_s, j.record += records;
      for (size_t k = 0; k < j.position.size() && k < counts.size(); ++k)
        j.position[k] += counts[k];
    }
  }
  for (auto& [topic, odometry] : bag->odometry) {
    for (Odometry& o : odometry) o.stamp_s += dt_s, o.log_time_s += dt_s, o.record += records;
  }
}

template <typename T>
void Append(std::map<std::string, std::vector<T>>&& from,
            std::map<std::string, std::vector<T>>* to) {
  for (auto& [topic, messages] : from) {
    std::vector<T>& into = (*to)[topic];
    into.insert(into.end(), std::make_move_iterator(messages.begin()),
                std::make_move_iterator(messages.end()));
  }
}

// Gap put between a log and the next when their clocks overlap.
constexpr double kJoinGapS = 10.0;
// How deep and how far a directory is searched for logs (an archive of experiments is one or two
// levels deep; a directory given by mistake, such as a home, is not walked whole).
constexpr int kMaxDepth = 3;
constexpr int kMaxEntries = 10000;

}  // namespace

bool IsCsmLogDirectory(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_directory(path, ec) && !CsmLogsIn(path).empty();
}

std::vector<std::string> CsmLogsIn(const std::string& directory) {
  std::vector<std::string> logs;
  std::error_code ec;
  int entries = 0;
  for (auto it = std::filesystem::recursive_directory_iterator(directory, ec);
       !ec && it != std::filesystem::recursive_directory_iterator() && ++entries <= kMaxEntries;
       it.increment(ec)) {
    if (it.depth() >= kMaxDepth) it.disable_recursion_pending();
    if (it->is_regular_file(ec) && LooksLikeCsmLog(it->path().string())) {
      logs.push_back(it->path().string());
    }
  }
  std::sort(logs.begin(), logs.end());
  return logs;
}

StatusOr<RobotMessages> ReadCsmLogs(const std::vector<std::string>& paths,
                                    const std::string& source) {
  std::vector<RobotMessages> logs;
  for (const std::string& path : paths) {
    CALIB_ASSIGN_OR_RETURN(RobotMessages log, ReadCsmLog(path));
    logs.push_back(std::move(log));
  }
  return JoinCsmLogs(std::move(logs), source);
}

StatusOr<RobotMessages> JoinCsmLogs(std::vector<RobotMessages> logs, const std::string& source) {
  if (logs.empty()) return Status::InvalidInput(source + ": no CSM laser logs");
  const auto first_stamp = [](const RobotMessages& m) {
    return m.scans.at(kCsmScanTopic).front().stamp_s;
  };
  std::stable_sort(logs.begin(), logs.end(), [&](const RobotMessages& a, const RobotMessages& b) {
    return first_stamp(a) < first_stamp(b);
  });
  RobotMessages out = std::move(logs.front());
  for (size_t k = 1; k < logs.size(); ++k) {
    RobotMessages& log = logs[k];
    if (out.joint_states.count(kCsmEncoderTopic) != log.joint_states.count(kCsmEncoderTopic)) {
      return Status::InvalidInput(log.source + ": its records " +
                                  (log.joint_states.count(kCsmEncoderTopic) ? "have" : "lack") +
                                  " the wheels' encoder counts, unlike " + out.source +
                                  "'s: are they one robot's logs?");
    }
    const double end_s = out.scans.at(kCsmScanTopic).back().stamp_s;
    const double dt_s = first_stamp(log) > end_s ? 0.0 : end_s + kJoinGapS - first_stamp(log);
    std::vector<double> counts;
    const auto joints = out.joint_states.find(kCsmEncoderTopic);
    if (joints != out.joint_states.end()) {
      const std::vector<double>& last = joints->second.back().position;
      const std::vector<double>& first = log.joint_states.at(kCsmEncoderTopic).front().position;
      counts = {last[0] - first[0], last[1] - first[1]};
    }
    int64_t records = 0;
    for (const auto& [topic, scans] : out.scans)
      records = std::max(records, scans.back().record + 1);
    Shift(dt_s, counts, records, &log);
    out.restarts_s.push_back(first_stamp(log));
    Append(std::move(log.scans), &out.scans);
    Append(std::move(log.joint_states), &out.joint_states);
    Append(std::move(log.odometry), &out.odometry);
  }
  for (TopicInfo& topic : out.topics) {
    if (topic.type == "sensor_msgs/LaserScan") topic.message_count = out.scans[topic.name].size();
    if (topic.type == "sensor_msgs/JointState") {
      topic.message_count = out.joint_states[topic.name].size();
    }
    if (topic.type == "nav_msgs/Odometry") topic.message_count = out.odometry[topic.name].size();
  }
  out.source = source;
  return out;
}

}  // namespace calib
