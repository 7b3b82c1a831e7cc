#include <calib/core/bag/robot_messages_join.h>
#include <calib/core/scan/csm_log.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace calib {
namespace {

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
  for (const RobotMessages& log : logs) {
    if (log.joint_states.count(kCsmEncoderTopic) !=
        logs.front().joint_states.count(kCsmEncoderTopic)) {
      return Status::InvalidInput(log.source + ": its records " +
                                  (log.joint_states.count(kCsmEncoderTopic) ? "have" : "lack") +
                                  " the wheels' encoder counts, unlike " + logs.front().source +
                                  "'s: are they one robot's logs?");
    }
  }
  return JoinRecordings(std::move(logs), source);
}

}  // namespace calib
