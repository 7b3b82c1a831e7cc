#ifndef CALIB_CORE_BAG_ROBOT_MESSAGES_H_
#define CALIB_CORE_BAG_ROBOT_MESSAGES_H_

#include <calib/core/scan/laser_scan.h>
#include <calib/core/status.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

// The messages of a robot's recording that a calibration uses, decoded from a ROS 2 bag (MCAP or
// sqlite3, CDR) or a ROS 1 bag (v2.0), with no ROS installation. Every message keeps its header
// stamp (stamp_s, the driver's idea of the sample time), the bag's log time (log_time_s, when the
// recorder received it) and its record index, so that errors name it and the timing diagnostics
// can compare the two clocks.
namespace calib {

struct JointState {  // sensor_msgs/JointState
  double stamp_s = 0.0, log_time_s = 0.0;
  int64_t record = 0;
  std::string frame_id;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;  // Each empty or one per name.
};

struct Odometry {  // nav_msgs/Odometry, the planar part kept plus z and the full quaternion.
  double stamp_s = 0.0, log_time_s = 0.0;
  int64_t record = 0;
  std::string frame_id, child_frame_id;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();   // In child_frame_id.
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // In child_frame_id.
};

struct TransformStamped {  // geometry_msgs/TransformStamped
  double stamp_s = 0.0, log_time_s = 0.0;
  int64_t record = 0;
  std::string parent_frame, child_frame;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

struct TopicInfo {
  std::string name;
  // Normalised to "package/Type" (ROS 2's "sensor_msgs/msg/LaserScan" → "sensor_msgs/LaserScan").
  std::string type;
  int64_t message_count = 0;
};

// A topic of a type the readers do not decode themselves, kept as bytes (a robot's own encoder
// message, decoded through its definition: message_definition.h).
struct RawMessage {
  double log_time_s = 0.0;
  int64_t record = 0;
  std::vector<uint8_t> data;
};

struct RawTopic {
  std::string type;        // Normalised "package/Type".
  std::string definition;  // As the bag stores it (with dependencies); empty when it stores none.
  bool cdr = true;         // ROS 2 CDR; else ROS 1 serialization.
  std::vector<RawMessage> messages;  // In log-time order.
};

struct RobotMessages {
  std::string source;             // The file read.
  std::vector<TopicInfo> topics;  // Every topic in the bag, whatever its type.
  // By topic name, in log-time order; only topics of these types are decoded.
  std::map<std::string, std::vector<LaserScan>> scans;
  std::map<std::string, std::vector<JointState>> joint_states;
  std::map<std::string, std::vector<Odometry>> odometry;
  std::vector<TransformStamped> tf, tf_static;  // From /tf and /tf_static (tf2_msgs/TFMessage).
  // Topics kept raw: every topic of a known encoder type (encoder_messages.h) and those asked for.
  std::map<std::string, RawTopic> raw;
  // JointState topics whose positions are raw encoder counts (a log that is no bag: csm_log.h),
  // with the counts per wheel turn its source implies, 0 when it does not say.
  std::map<std::string, double> joint_counts_per_turn;
  // Which robot the source's counts per turn are known for, for the output.
  std::string counts_per_turn_source;
  // Where a recording joined from several logs starts again (the first stamp of each log after
  // the first): nothing spans them.
  std::vector<double> restarts_s;
};

struct BagReadOptions {
  // Topics to decode; empty: every topic of a type above.
  std::set<std::string> topics;
  // Topics to keep raw whatever their type (in `topics` too when that is not empty).
  std::set<std::string> raw_topics;
};

// A ROS 2 bag: an .mcap file, or a bag directory holding one (metadata.yaml beside it).
StatusOr<RobotMessages> ReadMcapBag(const std::string& path, const BagReadOptions& options = {});

// A ROS 2 bag in rosbag2's sqlite3 storage: a .db3 file, a .db3.zstd file (compression_mode
// FILE), or a bag directory holding them (split files read as one); messages zstd-compressed one
// by one (compression_mode MESSAGE) are decompressed.
StatusOr<RobotMessages> ReadSqliteBag(const std::string& path, const BagReadOptions& options = {});

// Whether `directory` holds a .db3 or .db3.zstd file.
bool HoldsSqliteBag(const std::string& directory);

// A ROS 1 bag, format 2.0 (uncompressed, bz2 or lz4 chunks).
StatusOr<RobotMessages> ReadRos1Bag(const std::string& path, const BagReadOptions& options = {});

// The same over a file's bytes in memory; `source` names them in messages.
StatusOr<RobotMessages> ReadMcapBytes(std::string_view bytes, const std::string& source,
                                      const BagReadOptions& options = {});
StatusOr<RobotMessages> ReadSqliteBytes(std::string_view bytes, const std::string& source,
                                        const BagReadOptions& options = {});
StatusOr<RobotMessages> ReadRos1BagBytes(std::string_view bytes, const std::string& source,
                                         const BagReadOptions& options = {});

}  // namespace calib

#endif  // CALIB_CORE_BAG_ROBOT_MESSAGES_H_
