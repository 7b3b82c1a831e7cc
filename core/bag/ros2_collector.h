#ifndef CALIB_CORE_BAG_ROS2_COLLECTOR_H_
#define CALIB_CORE_BAG_ROS2_COLLECTOR_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/status.h>

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

// What both ROS 2 storages (MCAP, rosbag2's sqlite3) share once their records are read: the
// topics' kinds, the CDR messages decoded into RobotMessages in log-time order, and the files of
// a bag directory read one after the other.
namespace calib::ros2 {

// "sensor_msgs/msg/LaserScan" → "sensor_msgs/LaserScan".
std::string NormalisedType(const std::string& name);

// kRaw: kept as bytes (RobotMessages::raw).
enum class Kind { kNone, kScan, kJoints, kOdometry, kTf, kTfStatic, kRaw };

// The kind of a topic of (normalised) `type` whose messages are in `encoding`; kNone for what a
// calibration does not read.
Kind KindOf(const std::string& topic, const std::string& type, const std::string& encoding);

struct Channel {
  std::string topic, type;
  std::string definition;  // For kRaw: the message definition the bag stores, if any.
  bool cdr = true;         // For kRaw: CDR (else ROS 1 serialization, in a ROS 1 MCAP).
  Kind kind = Kind::kNone;
  bool wanted = false;
  int64_t message_count = 0;
};

// A channel of `topic` and `type` (ROS 2 or normalised), wanted when its kind is read and the
// options name it or name no topic. A topic of another type is kept raw (kRaw, with
// `definition`) when it is of a known encoder type or the options ask for it.
Channel MakeChannel(const std::string& topic, const std::string& type, const std::string& encoding,
                    const BagReadOptions& options, const std::string& definition = "");

// Decodes messages as they come and hands them out sorted by (log time, record).
class MessageCollector {
 public:
  // The CDR message `data` of `channel` (a wanted one), logged at `log_time_ns`, the bag's
  // `record`-th message.
  Status Decode(const Channel& channel, uint64_t log_time_ns, const uint8_t* data, uint64_t size,
                int64_t record);
  // The decoded messages into *out (its topics are the caller's).
  void Finish(RobotMessages* out);

 private:
  template <typename T>
  using Logged = std::vector<std::pair<uint64_t, T>>;
  std::map<std::string, Logged<LaserScan>> scans_;
  std::map<std::string, Logged<JointState>> joints_;
  std::map<std::string, Logged<Odometry>> odometry_;
  Logged<TransformStamped> tf_, tf_static_;
  std::map<std::string, std::pair<RawTopic, Logged<RawMessage>>> raw_;
};

// A bag directory's files whose names end in `suffix` (several when rosbag2 split the
// recording by size or time), in the order their names count them (run_2 before run_10); an
// error naming the directory when there is none.
StatusOr<std::vector<std::string>> BagDirectoryFiles(const std::string& directory,
                                                     const std::string& suffix);

// The files of a split bag read one after the other by `read_file`, as one recording: records
// numbered on from file to file, every topic kept in log-time order.
template <typename ReadFile>
StatusOr<RobotMessages> ReadSplitBag(const std::string& path, const std::vector<std::string>& files,
                                     const ReadFile& read_file);

// `part` appended to `all`, its records numbered on after `record_base`; returns the next
// file's base.
int64_t AppendBagPart(RobotMessages&& part, int64_t record_base, RobotMessages* all);

template <typename ReadFile>
StatusOr<RobotMessages> ReadSplitBag(const std::string& path, const std::vector<std::string>& files,
                                     const ReadFile& read_file) {
  RobotMessages all;
  all.source = path;
  int64_t record_base = 0;
  for (const std::string& file : files) {
    CALIB_ASSIGN_OR_RETURN(RobotMessages part, read_file(file));
    record_base = AppendBagPart(std::move(part), record_base, &all);
  }
  return all;
}

}  // namespace calib::ros2

#endif  // CALIB_CORE_BAG_ROS2_COLLECTOR_H_
