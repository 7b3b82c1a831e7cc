#include <calib/core/bz2_decompress.h>
#include <calib/core/scan/csm_log.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <utility>

namespace calib {
namespace {

using nlohmann::json;

// How far a beam's "theta" may lie off its scan's even grid (rad): Hokuyo and SICK angles are
// exact steps; more says the beams are not one scan's.
constexpr double kGridToleranceRad = 1e-4;
// Nearer readings are no return: below every lidar's range, where a Hokuyo's error codes sit
// (1–19 mm: no echo, too bright, ...).
constexpr double kMinReadingM = 0.02;
// No lidar's median return is this far (m): beyond, the readings are in another unit.
constexpr double kMaxMedianRangeM = 100.0;
// The bytes read to tell the format (after decompression).
constexpr size_t kSniffBytes = 64 * 1024;
// A whole log decompresses to at most this much.
constexpr size_t kMaxTextBytes = size_t{8} << 30;

bool IsSpace(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

bool IsBz2(std::string_view bytes) { return bytes.substr(0, 3) == "BZh"; }

// Where a record starts, for messages.
std::string Where(const std::string& source, int64_t record, int64_t line) {
  return source + " record " + std::to_string(record) + " (line " + std::to_string(line) + ")";
}

// Python's json writes NaN and Infinity, which JSON has not: read as null.
std::string NullForNonFinite(std::string_view text) {
  std::string out;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      out += c;
      if (c == '\\' && i + 1 < text.size()) out += text[++i];
      if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') in_string = true;
    bool replaced = false;
    for (std::string_view word : {"-Infinity", "Infinity", "NaN", "-inf", "inf", "nan"}) {
      if (text.substr(i, word.size()) == word) {
        out += "null";
        i += word.size() - 1;
        replaced = true;
        break;
      }
    }
    if (!replaced) out += c;
  }
  return out;
}

std::optional<double> Number(const json& j) {
  if (j.is_number()) return j.get<double>();
  return std::nullopt;
}

// [s, µs] (CSM's struct timeval), or seconds as one number; nullopt when absent or unset (−1).
std::optional<double> Stamp(const json& record, const char* key) {
  const auto it = record.find(key);
  if (it == record.end()) return std::nullopt;
  if (it->is_number()) return it->get<double>();
  if (!it->is_array() || it->size() != 2) return std::nullopt;
  const std::optional<double> s = Number((*it)[0]), us = Number((*it)[1]);
  if (!s || !us || *s < 0.0 || *us < 0.0) return std::nullopt;
  return *s + 1e-6 * *us;
}

struct EncoderReading {
  double left_t, left, right_t, right;
  int64_t record;
};

class CsmParser {
 public:
  CsmParser(std::string_view text, const std::string& source) : text_(text), source_(source) {}

  StatusOr<RobotMessages> Parse() {
    size_t p = 0;
    while (true) {
      p = SkipSpace(p);
      if (p >= text_.size()) break;
      const int64_t line = line_;
      CALIB_ASSIGN_OR_RETURN(const size_t end, RecordEnd(p, line));
      CALIB_RETURN_IF_ERROR(Record(text_.substr(p, end - p), line));
      CountLines(p, end);
      p = end;
      ++record_;
    }
    return Finish();
  }

 private:
  size_t SkipSpace(size_t p) {
    while (p < text_.size() && IsSpace(text_[p])) {
      if (text_[p] == '\n') ++line_;
      ++p;
    }
    return p;
  }
  void CountLines(size_t begin, size_t end) {
    line_ += std::count(text_.begin() + begin, text_.begin() + end, '\n');
  }

  // One past the '}' that closes the object at p.
  StatusOr<size_t> RecordEnd(size_t p, int64_t line) const {
    if (text_[p] != '{') {
      return Status::InvalidInput(Where(source_, record_, line) +
                                  ": expected a JSON object ('{'), "
                                  "found '" +
                                  std::string(text_.substr(p, 20)) + "'");
    }
    int depth = 0;
    bool in_string = false;
    const size_t limit = std::min(text_.size(), p + kMaxLineBytes);
    for (size_t i = p; i < limit; ++i) {
      const char c = text_[i];
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
    if (limit < text_.size()) {
      return Status::InvalidInput(Where(source_, record_, line) + ": longer than " +
                                  std::to_string(kMaxLineBytes >> 20) + " MB (not a scan record?)");
    }
    return Status::InvalidInput(Where(source_, record_, line) +
                                ": the file ends inside the record (truncated)");
  }

  Status Record(std::string_view bytes, int64_t line) {
    json record = json::parse(bytes.begin(), bytes.end(), nullptr, false);
    if (record.is_discarded()) {
      const std::string nulled = NullForNonFinite(bytes);
      record = json::parse(nulled, nullptr, false);
    }
    const std::string where = Where(source_, record_, line);
    if (record.is_discarded() || !record.is_object()) {
      return Status::InvalidInput(where + ": not a JSON object");
    }
    if (!record.contains("readings")) {
      return Status::InvalidInput(where + ": no \"readings\" (the ranges of a scan)" +
                                  (record_ == 0 ? ": is it a CSM laser log?" : ""));
    }
    const std::optional<double> t = Stamp(record, "timestamp");
    if (!t) {
      return Status::InvalidInput(where + ": no \"timestamp\" ([seconds, microseconds])");
    }
    CALIB_RETURN_IF_ERROR(Scan(record, *t, where));
    CALIB_RETURN_IF_ERROR(Encoders(record, *t, where));
    ReadOdometry(record, *t);
    return Status::Ok();
  }

  // The beams' angles: "theta", or min_theta..max_theta over nrays.
  Status Angles(const json& record, size_t n, const std::string& where, LaserScan* scan) const {
    const auto theta = record.find("theta");
    if (theta != record.end() && theta->is_array() && theta->size() == n) {
      std::vector<double> a(n);
      for (size_t i = 0; i < n; ++i) {
        const std::optional<double> v = Number((*theta)[i]);
        if (!v || !std::isfinite(*v)) {
          return Status::InvalidInput(where + ": theta[" + std::to_string(i) + "] is no number");
        }
        a[i] = *v;
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
    if (theta != record.end()) {
      return Status::InvalidInput(where + ": \"theta\" must hold one angle per reading (" +
                                  std::to_string(n) + ")");
    }
    const std::optional<double> lo =
        record.contains("min_theta") ? Number(record["min_theta"]) : std::nullopt;
    const std::optional<double> hi =
        record.contains("max_theta") ? Number(record["max_theta"]) : std::nullopt;
    if (!lo || !hi || !std::isfinite(*lo) || !std::isfinite(*hi)) {
      return Status::InvalidInput(where +
                                  ": no beam angles (\"theta\", or \"min_theta\" and "
                                  "\"max_theta\")");
    }
    scan->angle_min_rad = *lo;
    scan->angle_increment_rad = n > 1 ? (*hi - *lo) / (n - 1) : 0.0;
    return Status::Ok();
  }

  Status Scan(const json& record, double t, const std::string& where) {
    const auto readings = record.find("readings");
    if (readings == record.end() || !readings->is_array() || readings->empty()) {
      return Status::InvalidInput(where + ": \"readings\" must be a non-empty array of ranges");
    }
    const size_t n = readings->size();
    if (record.contains("nrays") && Number(record["nrays"]) != static_cast<double>(n)) {
      return Status::InvalidInput(where + ": nrays is not the number of readings (" +
                                  std::to_string(n) + ")");
    }
    LaserScan scan;
    scan.stamp_s = scan.log_time_s = t;
    scan.record = record_;
    scan.frame_id = "laser";
    scan.range_max_m = std::numeric_limits<double>::infinity();
    CALIB_RETURN_IF_ERROR(Angles(record, n, where, &scan));
    const double span_rad = std::abs(scan.angle_increment_rad) * (n - 1);
    if (span_rad > 2.0 * M_PI + 1e-6) {
      return Status::InvalidInput(where + ": the beams span " + Num(span_rad) +
                                  " rad, more than a circle: are the angles in degrees? (CSM "
                                  "logs hold radians)");
    }
    const auto valid = record.find("valid");
    const bool has_valid = valid != record.end() && valid->is_array() && valid->size() == n;
    scan.ranges_m.resize(n);
    for (size_t i = 0; i < n; ++i) {
      const std::optional<double> r = Number((*readings)[i]);
      const bool ok =
          r && *r >= kMinReadingM && (!has_valid || Number((*valid)[i]).value_or(0.0) != 0.0);
      scan.ranges_m[i] = ok ? static_cast<float>(*r) : std::numeric_limits<float>::quiet_NaN();
    }
    scans_.push_back(std::move(scan));
    return Status::Ok();
  }

  Status Encoders(const json& record, double t, const std::string& where) {
    const bool left = record.contains("left"), right = record.contains("right");
    if (!left && !right) return Status::Ok();
    const std::optional<double> l = left ? Number(record["left"]) : std::nullopt;
    const std::optional<double> r = right ? Number(record["right"]) : std::nullopt;
    if (!l || !r || !std::isfinite(*l) || !std::isfinite(*r)) {
      return Status::InvalidInput(where + ": \"left\" and \"right\" must both be encoder counts");
    }
    const std::optional<double> lt = Stamp(record, "leftTimestamp");
    const std::optional<double> rt = Stamp(record, "rightTimestamp");
    own_stamps_ = own_stamps_ || (lt && rt);
    encoders_.push_back({lt.value_or(t), *l, rt.value_or(t), *r, record_});
    return Status::Ok();
  }

  void ReadOdometry(const json& record, double t) {
    const auto odometry = record.find("odometry");
    if (odometry == record.end() || !odometry->is_array() || odometry->size() != 3) return;
    double v[3];
    for (int k = 0; k < 3; ++k) {
      const std::optional<double> x = Number((*odometry)[k]);
      if (!x || !std::isfinite(*x)) return;
      v[k] = *x;
    }
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

  StatusOr<RobotMessages> Finish() {
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

  std::string_view text_;
  const std::string& source_;
  int64_t record_ = 0, line_ = 1;
  std::vector<LaserScan> scans_;
  std::vector<EncoderReading> encoders_;
  std::vector<Odometry> odometry_;
  bool own_stamps_ = false, moved_ = false;
};

StatusOr<std::string> Decompressed(std::string_view bytes, const std::string& path) {
  std::string text;
  bool ended = false;
  const Status s = Bz2Decompress(bytes, {kMaxTextBytes, true}, &text, &ended);
  if (!s.ok()) return Status::InvalidInput(path + ": " + s.message());
  if (!ended && text.size() >= kMaxTextBytes) {
    return Status::InvalidInput(path + ": decompresses to more than " +
                                std::to_string(kMaxTextBytes >> 30) + " GiB");
  }
  return text;
}

}  // namespace

bool IsBz2File(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  const StatusOr<MappedFile> file = MappedFile::Open(path);
  return file.ok() && IsBz2(file->text());
}

bool LooksLikeCsmLog(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  StatusOr<MappedFile> file = MappedFile::Open(path);
  if (!file.ok()) return false;
  std::string_view head = file->text().substr(0, kSniffBytes);
  std::string unpacked;
  if (IsBz2(file->text())) {
    bool ended = false;
    if (!Bz2Decompress(file->text(), {kSniffBytes, true}, &unpacked, &ended).ok()) return false;
    head = unpacked;
  }
  const size_t first = head.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos || head[first] != '{') return false;
  // The first object's keys: a tuple file's are T, phi_l, ...
  const size_t next = head.find("}{", first);
  const std::string_view object =
      head.substr(first, next == std::string_view::npos ? head.size() : next - first);
  return object.find("\"readings\"") != std::string_view::npos;
}

StatusOr<RobotMessages> ReadCsmLogText(std::string_view text, const std::string& source) {
  return GuardAllocation(source, [&] { return CsmParser(text, source).Parse(); });
}

StatusOr<RobotMessages> ReadCsmLog(const std::string& path) {
  CALIB_ASSIGN_OR_RETURN(const MappedFile file, MappedFile::Open(path));
  if (!IsBz2(file.text())) return ReadCsmLogText(file.text(), path);
  return GuardAllocation(path, [&]() -> StatusOr<RobotMessages> {
    CALIB_ASSIGN_OR_RETURN(const std::string text, Decompressed(file.text(), path));
    return ReadCsmLogText(text, path);
  });
}

}  // namespace calib
