#ifndef CALIB_CORE_SCAN_CSM_LOG_H_
#define CALIB_CORE_SCAN_CSM_LOG_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/encoder_sample.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/core/status.h>

#include <memory>
#include <string>
#include <string_view>
#include <vector>

// A laser log in the JSON format of Censi's Canonical Scan Matcher (CSM), as the raw logs of
// Censi et al. (2013) hold it: a stream of JSON objects, one per scan, optionally bzip2-compressed
// (log.log.bz2). Each object holds
//   "readings": ranges in m (null, NaN or under 2 cm, where a Hokuyo's error codes sit: no
//   return), "valid": 0/1 per beam (optional),
//   "theta": each beam's angle in rad, or "min_theta", "max_theta" and "nrays",
//   "timestamp": [s, µs] (the scan's time),
// and from the robot either
//   "left", "right": the wheel encoders' counts, with "leftTimestamp", "rightTimestamp" ([s, µs],
//   when each was read; the scan's time without them), or
//   "odometry": [x, y, θ], the robot's own dead reckoning.
// Other fields are ignored. It is read as a bag would be: the scans on a topic "scans" (frame
// "laser"), the counts as the joints "left_wheel" and "right_wheel" of a JointState topic
// "encoders" (in counts: RobotMessages::joint_counts_per_turn), the odometry as a topic
// "odometry". Each wheel's counts are read at the midpoint of the two encoders' stamps, each
// interpolated along its own readings; a reading repeated under its stamp (attached to the next
// scan again) is one sample.
namespace calib {

// The topics a CSM log is read onto.
inline constexpr const char* kCsmScanTopic = "scans";
inline constexpr const char* kCsmEncoderTopic = "encoders";
inline constexpr const char* kCsmOdometryTopic = "odometry";

// The counts per wheel turn of the Khepera III in Censi et al.'s logs (their synchronizer's
// ticks_to_rad = 2π / (691.2 · 4): 691.2 lines a turn, ×4 for the quadrature). A log whose
// encoders carry their own stamps (leftTimestamp) is theirs.
constexpr double kCensiKheperaCountsPerTurn = 691.2 * 4.0;

// Whether `path` is a regular file (plain or .bz2) whose first JSON object has "readings".
bool LooksLikeCsmLog(const std::string& path);
// Whether `path` is a regular file that starts as bzip2 data do ("BZh").
bool IsBz2File(const std::string& path);

StatusOr<RobotMessages> ReadCsmLog(const std::string& path);

// Whether `path` is a directory holding CSM logs (in it or its subdirectories, three levels at
// most: an archive of experiments such as the authors' exp*/log.log.bz2), and those logs,
// sorted by path.
bool IsCsmLogDirectory(const std::string& path);
std::vector<std::string> CsmLogsIn(const std::string& directory);

// Several logs of one robot (the experiments of one configuration) as one recording, named
// `source` (JoinRecordings: a log that does not continue the one before starts again, moved
// after it where its clock overlaps, its counts going on from the previous log's).
StatusOr<RobotMessages> ReadCsmLogs(const std::vector<std::string>& paths,
                                    const std::string& source);
// The same over logs read (ReadCsmLog, ReadCsmLogText).
StatusOr<RobotMessages> JoinCsmLogs(std::vector<RobotMessages> logs, const std::string& source);

// The same over the (decompressed) text; `source` names it in messages.
StatusOr<RobotMessages> ReadCsmLogText(std::string_view text, const std::string& source);

// The same over text that arrives in pieces, cut anywhere (a record a piece ends inside waits for
// the next): memory for the scans, not for the text.
class CsmLogReader {
 public:
  explicit CsmLogReader(std::string source);
  ~CsmLogReader();
  CsmLogReader(const CsmLogReader&) = delete;
  CsmLogReader& operator=(const CsmLogReader&) = delete;

  // The first bad record's error, naming it; the reader is then done.
  Status Feed(std::string_view piece);
  // The log read: an error when it ends inside a record (truncated) or holds no scan.
  StatusOr<RobotMessages> Finish();

 private:
  class Parser;
  std::string source_;
  std::unique_ptr<Parser> parser_;
  Status error_ = Status::Ok();
};

// A simulated robot's scans and wheel angles as such a log: each scan with the counts (rounded,
// `counts_per_turn` a wheel turn) and stamps of the latest encoder sample at or before it, every
// time shifted by epoch_s.
std::string CsmLogText(const std::vector<LaserScan>& scans,
                       const std::vector<EncoderSample>& encoders, double counts_per_turn,
                       double epoch_s);

}  // namespace calib

#endif  // CALIB_CORE_SCAN_CSM_LOG_H_
