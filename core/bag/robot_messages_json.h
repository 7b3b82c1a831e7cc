#ifndef CALIB_CORE_BAG_ROBOT_MESSAGES_JSON_H_
#define CALIB_CORE_BAG_ROBOT_MESSAGES_JSON_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/status.h>

#include <string>

// RobotMessages as the bag generators' robot-messages JSON (data/bags/README.md):
//   {"topics": [{"name", "type"}...], "messages": [{"topic", "log_time_ns", "msg"}...]}
// with the messages of every topic merged in log-time order (stable: within one log time, scans,
// joint states, odometry, /tf, /tf_static). Consecutive transforms of /tf (or /tf_static) that
// share a log time go into one tf2_msgs/TFMessage. NaN and ±inf ranges are written as the strings
// "nan", "inf", "-inf"; other non-finite numbers as well. Invalid UTF-8 in names is replaced.
namespace calib {

std::string RobotMessagesJson(const RobotMessages& messages);
Status WriteRobotMessagesJson(const RobotMessages& messages, const std::string& path);

}  // namespace calib

#endif  // CALIB_CORE_BAG_ROBOT_MESSAGES_JSON_H_
