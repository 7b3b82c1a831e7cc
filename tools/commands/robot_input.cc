#include <calib/core/bag/robot_bag.h>
#include <calib/core/bag/robot_messages_join.h>
#include <calib/core/scan/csm_log.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/core/scan/scan_directory.h>
#include <calib/core/text_number.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/laser_input.h>
#include <calib/tools/commands/robot_input.h>

#include <algorithm>
#include <filesystem>
#include <vector>

namespace calib::cli {
namespace {

// No spinning lidar turns slower than this (the slowest turn at a few Hz).
constexpr double kLongestRotationPeriodS = 10.0;

// The CSM laser logs `input` names: one, several separated by commas, or a directory of them
// (the experiments of one configuration); empty when it names none. A bzip2 file is taken for
// one (no other input is compressed so), so that a corrupt one is named as such.
std::vector<std::string> CsmLogsOf(const std::string& input) {
  std::error_code ec;
  if (std::filesystem::is_directory(input, ec)) {
    return LooksLikeRobotBag(input) ? std::vector<std::string>() : CsmLogsIn(input);
  }
  // One that is names them all: the others' errors then say what is wrong with them.
  const std::vector<std::string> paths = SplitCommas(input);
  for (const std::string& path : paths) {
    if (LooksLikeCsmLog(path) || IsBz2File(path)) return paths;
  }
  return {};
}

// Several bags of one robot separated by commas (a bag split in parts, the runs of a session);
// empty unless every part is a bag.
std::vector<std::string> BagsOf(const std::string& input) {
  const std::vector<std::string> paths = SplitCommas(input);
  if (paths.size() < 2) return {};
  for (const std::string& path : paths) {
    if (!LooksLikeRobotBag(path)) return {};
  }
  return paths;
}

StatusOr<RobotMessages> ReadBags(const std::vector<std::string>& paths, const std::string& input,
                                 const BagReadOptions& read) {
  std::vector<RobotMessages> parts;
  for (const std::string& path : paths) {
    CALIB_ASSIGN_OR_RETURN(RobotMessages part, ReadRobotBag(path, read));
    parts.push_back(std::move(part));
  }
  return JoinRecordings(std::move(parts), input);
}

}  // namespace

bool IsRobotInput(const std::string& input) {
  return LooksLikeRobotBag(input) || IsScanDirectory(input) || !CsmLogsOf(input).empty() ||
         !BagsOf(input).empty();
}

StatusOr<RobotInput> ReadRobotInput(const CalibrateOptions& flags) {
  if (flags.timing == "off") {
    return Status::InvalidInput(flags.input +
                                ": a bag is calibrated with its timing; --timing off applies to "
                                "logs of intervals and stream directories");
  }
  RobotInput out;
  RobotBagOptions& o = out.options;
  o.topics.scan_topic = flags.scan_topic;
  o.topics.joint_state_topic = flags.joint_state_topic;
  o.topics.odom_topic = flags.odom_topic;
  o.topics.left_wheel_joint = flags.left_wheel_joint;
  o.topics.right_wheel_joint = flags.right_wheel_joint;
  o.topics.encoder_topic = flags.encoder_topic;
  o.topics.left_encoder_field = flags.left_encoder_field;
  o.topics.right_encoder_field = flags.right_encoder_field;
  o.base_frame = flags.base_frame;
  o.nominal_wheel_radius_m = flags.nominal_wheel_radius;
  o.nominal_wheelbase_m = flags.nominal_wheelbase;
  if (flags.scan_points) o.scan_points = ScanPointOptions();
  o.sensor_time_offset_s = flags.time_offset_s.value_or(0.0);
  CALIB_ASSIGN_OR_RETURN(o.wheel_radians_per_unit, WheelRadiansPerUnit(flags));
  const double period_s = flags.lidar_rotation_period_s;
  if (!(period_s >= 0.0 && period_s <= kLongestRotationPeriodS)) {
    return Status::InvalidInput("--lidar_rotation_period " + Num(period_s) +
                                ": the lidar's time for one turn in seconds (0.1 for 10 Hz), "
                                "between 0 (unknown) and " +
                                Num(kLongestRotationPeriodS));
  }
  if (flags.lidar_beam_timing != "auto" && flags.lidar_beam_timing != "driver") {
    return Status::InvalidInput("--lidar_beam_timing " + flags.lidar_beam_timing +
                                ": auto (checked against the scans) or driver (trusted)");
  }
  o.check_beam_timing = flags.lidar_beam_timing == "auto";
  if (flags.lidar_self_returns != "mask" && flags.lidar_self_returns != "keep") {
    return Status::InvalidInput("--lidar_self_returns " + flags.lidar_self_returns +
                                ": mask (the robot's own body left out) or keep");
  }
  o.mask_self_returns = flags.lidar_self_returns == "mask";
  if (!(flags.lidar_min_range_m >= 0.0 && flags.lidar_min_range_m < 100.0)) {
    return Status::InvalidInput("--lidar_min_range " + Num(flags.lidar_min_range_m) +
                                ": the nearest range (m) that is a return, in [0, 100)");
  }
  BagReadOptions read;
  if (!flags.encoder_topic.empty()) read.raw_topics.insert(flags.encoder_topic);
  if (IsScanDirectory(flags.input)) {
    CALIB_ASSIGN_OR_RETURN(out.bag, ReadScanDirectory(flags.input));
  } else if (const std::vector<std::string> logs = CsmLogsOf(flags.input); !logs.empty()) {
    CALIB_ASSIGN_OR_RETURN(out.bag, ReadCsmLogs(logs, flags.input));
  } else if (const std::vector<std::string> bags = BagsOf(flags.input); !bags.empty()) {
    CALIB_ASSIGN_OR_RETURN(out.bag, ReadBags(bags, flags.input, read));
  } else {
    CALIB_ASSIGN_OR_RETURN(out.bag, ReadRobotBag(flags.input, read));
  }
  if (period_s > 0.0) {
    for (auto& [topic, scans] : out.bag.scans) AssumeRotationPeriod(period_s, &scans);
  }
  for (auto& [topic, scans] : out.bag.scans) {
    for (LaserScan& scan : scans) {
      scan.range_min_m = std::max(scan.range_min_m, flags.lidar_min_range_m);
    }
  }
  return out;
}

}  // namespace calib::cli
