#include <calib/core/scan/csm_log.h>
#include <calib/core/scan/csm_record.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

namespace calib {
namespace {

// How far a beam's "theta" may lie off its scan's even grid (rad): Hokuyo and SICK angles are
// exact steps; more says the beams are not one scan's.
constexpr double kGridToleranceRad = 1e-4;
// Nearer readings are no return: below every lidar's range, where a Hokuyo's error codes sit
// (1–19 mm: no echo, too bright, ...).
constexpr double kMinReadingM = 0.02;
// No lidar's median return is this far (m): beyond, the readings are in another unit.
constexpr double kMaxMedianRangeM = 100.0;
// A record cut by a piece's end is completed from the next piece's first bytes, at least this many
// at a time.
constexpr size_t kCarryStepBytes = size_t{64} << 10;

bool IsSpace(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

// Where a record starts, for messages.
std::string Where(const std::string& source, int64_t record, int64_t line) {
  return source + " record " + std::to_string(record) + " (line " + std::to_string(line) + ")";
}

// [s, µs] (CSM's struct timeval), or seconds as one number; nullopt when absent or unset (−1).
std::optional<double> Stamp(const CsmValue& v) {
  if (v.IsNumber()) return v.number;
  if (!v.IsArray(2)) return std::nullopt;
  const double s = v.array[0], us = v.array[1];
  if (!(s >= 0.0) || !(us >= 0.0)) return std::nullopt;
  return s + 1e-6 * us;
}

struct EncoderReading {
  double left_t, left, right_t, right;
  int64_t record;
};

}  // namespace

class CsmLogReader::Parser {
 public:
  explicit Parser(const std::string& source) : source_(source) {}

  Status Feed(std::string_view piece) {
    // A record the last piece ended inside is completed from this one's first bytes (a growing
    // prefix, so that a long piece is not copied whole behind it).
    while (!carry_.empty() && !piece.empty()) {
      const size_t take = std::min(piece.size(), std::max(carry_.size(), kCarryStepBytes));
      carry_.append(piece.substr(0, take));
      piece.remove_prefix(take);
      size_t used = 0;
      CALIB_RETURN_IF_ERROR(Records(carry_, false, &used));
      carry_.erase(0, used);
    }
    if (!carry_.empty()) return Status::Ok();
    size_t used = 0;
    CALIB_RETURN_IF_ERROR(Records(piece, false, &used));
    carry_.assign(piece.substr(used));
    return Status::Ok();
  }

  StatusOr<RobotMessages> Finish() {
    size_t used = 0;
    CALIB_RETURN_IF_ERROR(Records(carry_, true, &used));
    return Messages();
  }

 private:
  // The whole records in `text`; *used: how many bytes they (and the space around them) take.
  Status Records(std::string_view text, bool last, size_t* used) {
    size_t p = 0;
    while (true) {
      const size_t begin = p;
      const int64_t begin_line = line_;
      p = SkipSpace(text, p);
      *used = p;
      if (p >= text.size()) return Status::Ok();
      const int64_t line = line_;
      CALIB_ASSIGN_OR_RETURN(const size_t end, RecordEnd(text, p, line, last));
      if (end == std::string_view::npos) {
        line_ = begin_line;  // Read again with the next piece.
        *used = begin;
        return Status::Ok();
      }
      CALIB_RETURN_IF_ERROR(Record(text.substr(p, end - p), line));
      line_ += std::count(text.begin() + p, text.begin() + end, '\n');
      p = end;
      ++record_;
    }
  }

  size_t SkipSpace(std::string_view text, size_t p) {
    while (p < text.size() && IsSpace(text[p])) {
      if (text[p] == '\n') ++line_;
      ++p;
    }
    return p;
  }

  // One past the '}' that closes the object at p; npos when the text ends first and more may
  // follow (not `last`).
  StatusOr<size_t> RecordEnd(std::string_view text, size_t p, int64_t line, bool last) const {
    if (text[p] != '{') {
      return Status::InvalidInput(Where(source_, record_, line) +
                                  ": expected a JSON object ('{'), "
                                  "found '" +
                                  std::string(text.substr(p, 20)) + "'");
    }
    int depth = 0;
    bool in_string = false;
    const size_t limit = std::min(text.size(), p + kMaxLineBytes);
    for (size_t i = p; i < limit; ++i) {
      const char c = text[i];
      if (in_string) {
        if (c == '\\')
          ++i;
        else if (c == '"')
          in_string = false;
      } else if (c == '"') {
        in_string = true;
      } else if (c == '{' || c == '[') {
        ++depth;
      } else if ((c == '}' || c == ']') && --depth == 0) {
        return i + 1;
      }
    }
    if (limit < text.size()) {
      return Status::InvalidInput(Where(source_, record_, line) + ": longer than " +
                                  std::to_string(kMaxLineBytes >> 20) + " MB (not a scan record?)");
    }
    if (!last) return std::string_view::npos;
    return Status::InvalidInput(Where(source_, record_, line) +
                                ": the file ends inside the record (truncated)");
  }

  Status Record(std::string_view bytes, int64_t line) {
    const std::string where = Where(source_, record_, line);
    if (!ParseCsmRecord(bytes, &record_fields_))
      return Status::InvalidInput(where + ": not a JSON object");
    const CsmRecord& r = record_fields_;
    if (!r.readings.present()) {
      return Status::InvalidInput(where + ": no \"readings\" (the ranges of a scan)" +
                                  (record_ == 0 ? ": is it a CSM laser log?" : ""));
    }
    const std::optional<double> t = Stamp(r.timestamp);
    if (!t) {
      return Status::InvalidInput(where + ": no \"timestamp\" ([seconds, microseconds])");
    }
    CALIB_RETURN_IF_ERROR(Scan(r, *t, where));
    CALIB_RETURN_IF_ERROR(Encoders(r, *t, where));
    ReadOdometry(r, *t);
    return Status::Ok();
  }

  // The beams' angles: "theta", or min_theta..max_theta over nrays.
  Status Angles(const CsmRecord& r, size_t n, const std::string& where, LaserScan* scan) const {
    if (r.theta.IsArray(n)) {
      const std::vector<double>& a = r.theta.array;
      for (size_t i = 0; i < n; ++i) {
        if (!std::isfinite(a[i])) {
          return Status::InvalidInput(where + ": theta[" + std::to_string(i) + "] is no number");
        }
      }
      scan->angle_min_rad = a[0];
      scan->angle_increment_rad = n > 1 ? (a[n - 1] - a[0]) / (n - 1) : 0.0;
      for (size_t i = 0; i < n; ++i) {
        if (std::abs(a[i] - scan->BeamAngle(static_cast<int>(i))) > kGridToleranceRad) {
          return Status::InvalidInput(where + ": theta[" + std::to_string(i) + "] = " + Num(a[i]) +
                                      " is off the scan's even grid of beam angles");
        }
      }
      return Status::Ok();
    }
    if (r.theta.present()) {
      return Status::InvalidInput(where + ": \"theta\" must hold one angle per reading (" +
                                  std::to_string(n) + ")");
    }
    if (!r.min_theta.IsNumber() || !r.max_theta.IsNumber()) {
      return Status::InvalidInput(where +
                                  ": no beam angles (\"theta\", or \"min_theta\" and "
                                  "\"max_theta\")");
    }
    scan->angle_min_rad = r.min_theta.number;
    scan->angle_increment_rad = n > 1 ? (r.max_theta.number - r.min_theta.number) / (n - 1) : 0.0;
    return Status::Ok();
  }

  Status Scan(const CsmRecord& r, double t, const std::string& where) {
    const size_t n = r.readings.array.size();
    if (r.readings.kind != CsmValue::Kind::kArray || n == 0) {
      return Status::InvalidInput(where + ": \"readings\" must be a non-empty array of ranges");
    }
    if (r.nrays.present() && !(r.nrays.IsNumber() && r.nrays.number == static_cast<double>(n))) {
      return Status::InvalidInput(where + ": nrays is not the number of readings (" +
                                  std::to_string(n) + ")");
    }
    LaserScan scan;
    scan.stamp_s = scan.log_time_s = t;
    scan.record = record_;
    scan.frame_id = "laser";
    scan.range_max_m = std::numeric_limits<double>::infinity();
    CALIB_RETURN_IF_ERROR(Angles(r, n, where, &scan));
    const double span_rad = std::abs(scan.angle_increment_rad) * (n - 1);
    if (span_rad > 2.0 * M_PI + 1e-6) {
      return Status::InvalidInput(where + ": the beams span " + Num(span_rad) +
                                  " rad, more than a circle: are the angles in degrees? (CSM "
                                  "logs hold radians)");
    }
    const bool has_valid = r.valid.IsArray(n);
    scan.ranges_m.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const double range = r.readings.array[i];
      // NaN (null) is no return, and so is a beam marked invalid (0 or null).
      const bool ok =
          range >= kMinReadingM && (!has_valid || r.valid.array[i] > 0.0 || r.valid.array[i] < 0.0);
      scan.ranges_m[i] = ok ? static_cast<float>(range) : std::numeric_limits<float>::quiet_NaN();
    }
    scans_.push_back(std::move(scan));
    return Status::Ok();
  }

  Status Encoders(const CsmRecord& r, double t, const std::string& where) {
    if (!r.left.present() && !r.right.present()) return Status::Ok();
    if (!r.left.IsNumber() || !r.right.IsNumber()) {
      return Status::InvalidInput(where + ": \"left\" and \"right\" must both be encoder counts");
    }
    const std::optional<double> lt = Stamp(r.left_timestamp);
    const std::optional<double> rt = Stamp(r.right_timestamp);
    own_stamps_ = own_stamps_ || (lt && rt);
    encoders_.push_back({lt.value_or(t), r.left.number, rt.value_or(t), r.right.number, record_});
    return Status::Ok();
  }

  void ReadOdometry(const CsmRecord& r, double t) {
    if (!r.odometry.IsArray(3)) return;
    const std::vector<double>& v = r.odometry.array;
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) return;
    Odometry o;
    o.stamp_s = o.log_time_s = t;
    o.record = record_;
    o.frame_id = "odom";
    o.child_frame_id = "base_link";
    o.position = Eigen::Vector3d(v[0], v[1], 0.0);
    o.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(v[2], Eigen::Vector3d::UnitZ()));
    moved_ = moved_ || v[0] != 0.0 || v[1] != 0.0 || v[2] != 0.0;
    odometry_.push_back(std::move(o));
  }

  // One wheel's readings, each stamp once (a reading attached to the next scan again is the same
  // reading), in time order.
  using Series = std::vector<std::pair<double, double>>;
  Series WheelSeries(bool left) const {
    Series s;
    for (const EncoderReading& e : encoders_) {
      const double t = left ? e.left_t : e.right_t;
      if (s.empty() || t > s.back().first) s.emplace_back(t, left ? e.left : e.right);
    }
    return s;
  }
  // Linear along the readings; beyond the first or last (by at most half the two encoders'
  // stamps apart) along the end segment.
  static double At(const Series& s, double t) {
    if (s.size() == 1) return s.front().second;
    auto hi = std::lower_bound(s.begin(), s.end(), std::make_pair(t, -HUGE_VAL));
    if (hi == s.begin()) ++hi;
    if (hi == s.end()) --hi;
    const auto lo = hi - 1;
    const double w = (t - lo->first) / (hi->first - lo->first);
    return lo->second + w * (hi->second - lo->second);
  }

  std::vector<JointState> Joints() const {
    std::vector<JointState> joints;
    if (encoders_.empty()) return joints;
    const Series left = WheelSeries(true), right = WheelSeries(false);
    double last_t = -HUGE_VAL;
    for (const EncoderReading& e : encoders_) {
      const double t = 0.5 * (e.left_t + e.right_t);
      if (!(t > last_t)) continue;
      last_t = t;
      JointState j;
      j.stamp_s = j.log_time_s = t;
      j.record = e.record;
      j.name = {"left_wheel", "right_wheel"};
      j.position = {At(left, t), At(right, t)};
      joints.push_back(std::move(j));
    }
    return joints;
  }

  // The median return of the first scans: a lidar's ranges in mm (a median of thousands of
  // "metres") would be matched as walls kilometres away.
  Status CheckRangeUnit() const {
    std::vector<float> returns;
    for (size_t k = 0; k < scans_.size() && k < 20; ++k) {
      for (size_t i = 0; i < scans_[k].ranges_m.size(); ++i) {
        if (scans_[k].IsReturn(static_cast<int>(i))) returns.push_back(scans_[k].ranges_m[i]);
      }
    }
    if (returns.empty()) return Status::Ok();
    std::nth_element(returns.begin(), returns.begin() + returns.size() / 2, returns.end());
    const double median_m = returns[returns.size() / 2];
    if (median_m <= kMaxMedianRangeM) return Status::Ok();
    return Status::InvalidInput(source_ + ": the first scans' median reading is " + Num(median_m) +
                                ": are the readings in millimetres? (CSM logs "
                                "hold metres)");
  }

  StatusOr<RobotMessages> Messages() {
    if (scans_.empty()) return Status::InvalidInput(source_ + ": no scan records (empty log)");
    CALIB_RETURN_IF_ERROR(CheckRangeUnit());
    RobotMessages out;
    out.source = source_;
    out.topics.push_back(
        {kCsmScanTopic, "sensor_msgs/LaserScan", static_cast<int64_t>(scans_.size())});
    out.scans[kCsmScanTopic] = std::move(scans_);
    std::vector<JointState> joints = Joints();
    if (!joints.empty()) {
      out.topics.push_back(
          {kCsmEncoderTopic, "sensor_msgs/JointState", static_cast<int64_t>(joints.size())});
      out.joint_states[kCsmEncoderTopic] = std::move(joints);
      out.joint_counts_per_turn[kCsmEncoderTopic] = own_stamps_ ? kCensiKheperaCountsPerTurn : 0.0;
      if (own_stamps_) {
        out.counts_per_turn_source = "the Khepera III of Censi et al.'s logs (their 691.2 × 4)";
      }
    }
    if (moved_) {
      out.topics.push_back(
          {kCsmOdometryTopic, "nav_msgs/Odometry", static_cast<int64_t>(odometry_.size())});
      out.odometry[kCsmOdometryTopic] = std::move(odometry_);
    }
    return out;
  }

  const std::string& source_;
  std::string carry_;  // The start of a record the last piece ended inside.
  CsmRecord record_fields_;
  int64_t record_ = 0, line_ = 1;
  std::vector<LaserScan> scans_;
  std::vector<EncoderReading> encoders_;
  std::vector<Odometry> odometry_;
  bool own_stamps_ = false, moved_ = false;
};

CsmLogReader::CsmLogReader(std::string source)
    : source_(std::move(source)), parser_(std::make_unique<Parser>(source_)) {}
CsmLogReader::~CsmLogReader() = default;

Status CsmLogReader::Feed(std::string_view piece) {
  if (!error_.ok()) return error_;
  error_ = GuardAllocation(source_, [&] { return parser_->Feed(piece); });
  return error_;
}

StatusOr<RobotMessages> CsmLogReader::Finish() {
  if (!error_.ok()) return error_;
  return GuardAllocation(source_, [&] { return parser_->Finish(); });
}

}  // namespace calib
