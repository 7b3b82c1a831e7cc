#ifndef CALIB_CORE_SCAN_SCAN_DIRECTORY_H_
#define CALIB_CORE_SCAN_SCAN_DIRECTORY_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/status.h>

#include <string>

// A robot's recording from anything that is not a bag: a directory holding scans.csv (the
// scans CSV of core/scan/scan_csv.h) and odometry.csv (t,left,right, cumulative wheel angles in
// rad), and no sensor_poses.csv. It is read as a bag would be: the scans on a topic named
// "scans.csv", the wheel angles as the joints "left_wheel" and "right_wheel" of a topic
// "odometry.csv".
namespace calib {

bool IsScanDirectory(const std::string& path);

StatusOr<RobotMessages> ReadScanDirectory(const std::string& path);

}  // namespace calib

#endif  // CALIB_CORE_SCAN_SCAN_DIRECTORY_H_
