#include <calib/core/laser/laser_log_io.h>
#include <calib/core/scan/scan_csv.h>
#include <calib/core/scan/scan_directory.h>
#include <calib/core/text_file.h>

#include <filesystem>

namespace calib {
namespace {
namespace fs = std::filesystem;
}  // namespace

bool IsScanDirectory(const std::string& path) {
  std::error_code ec;
  const fs::path dir(path);
  return fs::is_directory(dir, ec) && fs::exists(dir / "scans.csv", ec) &&
         !fs::exists(dir / "sensor_poses.csv", ec);
}

namespace {

StatusOr<RobotMessages> ReadDirectory(const std::string& path) {
  const fs::path dir(path);
  RobotMessages out;
  out.source = path;
  CALIB_ASSIGN_OR_RETURN(std::vector<LaserScan> scans, ReadScanCsv((dir / "scans.csv").string()));
  CALIB_ASSIGN_OR_RETURN(const std::vector<EncoderSample> wheels,
                         ReadOdometryCsv((dir / "odometry.csv").string()));
  // A bag's record is 0-based and becomes line record + 1 in the pose stream: the CSV's line.
  for (LaserScan& scan : scans) scan.record -= 1;
  std::vector<JointState> joints;
  for (const EncoderSample& s : wheels) {
    JointState j;
    j.stamp_s = j.log_time_s = s.t_s;
    j.record = s.line;
    j.name = {"left_wheel", "right_wheel"};
    j.position = {s.left_rad, s.right_rad};
    joints.push_back(std::move(j));
  }
  out.topics = {{"scans.csv", "sensor_msgs/LaserScan", static_cast<int64_t>(scans.size())},
                {"odometry.csv", "sensor_msgs/JointState", static_cast<int64_t>(joints.size())}};
  out.scans["scans.csv"] = std::move(scans);
  out.joint_states["odometry.csv"] = std::move(joints);
  return out;
}

}  // namespace

StatusOr<RobotMessages> ReadScanDirectory(const std::string& path) {
  return GuardAllocation(path, [&] { return ReadDirectory(path); });
}

}  // namespace calib
