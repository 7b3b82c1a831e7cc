#ifndef CALIB_CORE_BAG_ROBOT_MESSAGES_JOIN_H_
#define CALIB_CORE_BAG_ROBOT_MESSAGES_JOIN_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/status.h>

#include <string>
#include <vector>

// Several recordings of one robot as one: a ROS 1 bag split by size or duration, the runs of one
// calibration session, the experiments of a CSM archive.
namespace calib {

// In the order of their first scans. A recording that starts after the previous one ends, within
// a second, and whose wheel joints go on from where they were (steps like the previous one's
// last) continues it: a split bag, appended as it is. Any other starts again: it is appended with
// its start in RobotMessages::restarts_s (the scan matching starts anew there, so no interval
// spans the join), moved to start 10 s after the previous end where its clock began before it
// (a logger restarted), its joints' positions going on from the previous recording's last
// (counters reset). Message records are renumbered to follow on (errors then name the joined
// recording's record). Topics must keep their types.
StatusOr<RobotMessages> JoinRecordings(std::vector<RobotMessages> parts, const std::string& source);

}  // namespace calib

#endif  // CALIB_CORE_BAG_ROBOT_MESSAGES_JOIN_H_
