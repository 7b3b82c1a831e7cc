#ifndef CALIB_CORE_BAG_ROBOT_BAG_H_
#define CALIB_CORE_BAG_ROBOT_BAG_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/status.h>

#include <string>

// A robot's recording in any bag format, told apart by content: a ROS 2 bag (an .mcap file, a
// rosbag2 sqlite3 .db3 file, or a bag directory holding them and metadata.yaml) or a ROS 1 bag
// (v2.0).
namespace calib {

// Whether `path` is a bag: it is named .mcap, .bag, .db3 or .db3.zstd, its first bytes are
// MCAP's, ROS 1's or SQLite's magic, or it is a directory holding metadata.yaml or an .mcap,
// .db3 or .db3.zstd file. Reads a few bytes only.
bool LooksLikeRobotBag(const std::string& path);

StatusOr<RobotMessages> ReadRobotBag(const std::string& path, const BagReadOptions& options = {});

}  // namespace calib

#endif  // CALIB_CORE_BAG_ROBOT_BAG_H_
