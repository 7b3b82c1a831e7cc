#include <calib/core/csv.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <system_error>
#include <utility>

namespace calib {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Small text helpers.

// "source:line: record n: " with the parts that are known.
std::string Where(const std::string& source, int line, int record) {
  std::string where = source;
  if (line > 0) where += ":" + std::to_string(line);
  where += ": ";
  if (record > 0) where += "record " + std::to_string(record) + ": ";
  return where;
}

bool IsJsonSpace(char c) { return c == ' ' || c == '\n' || c == '\t' || c == '\r'; }

// ---------------------------------------------------------------------------------------------
// Checks shared by the tuple and CSV readers: T, the optional t, and the time line.

class LogBuilder {
 public:
  explicit LogBuilder(const std::string& source) { log_.source = source; }
  void Reserve(size_t n) { log_.intervals.reserve(n); }
  size_t size() const { return log_.intervals.size(); }

  // `interval.start_s` holds t when `has_t`; line and record are set.
  Status Add(LaserInterval interval, bool has_t) {
    // Built only on error: formatting it per record would dominate the parse time.
    const auto where = [&] { return Where(log_.source, interval.line, interval.record); };
    const double duration = interval.duration_s;
    if (!(duration > 0.0) || !std::isfinite(duration)) {
      return Status::InvalidInput(where() + "T must be positive and finite, got " + Num(duration));
    }
    if (log_.intervals.empty()) {
      has_t_ = has_t;
    } else if (has_t != has_t_) {
      const int first = log_.intervals.front().record;
      return Status::InvalidInput(
          where() + "t must be given in every record or in none: record " + std::to_string(first) +
          (has_t_ ? " has it, this one does not" : " does not, this one has it"));
    }
    if (log_.intervals.empty()) {
      if (!has_t) interval.start_s = 0.0;
      log_.intervals.push_back(std::move(interval));
      return Status::Ok();
    }
    const LaserInterval& previous = log_.intervals.back();
    const double previous_end = previous.start_s + previous.duration_s;
    if (!has_t) {
      interval.start_s = previous_end;
    } else {
      const double t = interval.start_s;
      if (!std::isfinite(t))
        return Status::InvalidInput(where() + "t must be finite, got " + Num(t));
      if (t < previous.start_s) {
        return Status::InvalidInput(where() + "t must be non-decreasing, got " + Num(t) +
                                    " after " + Num(previous.start_s));
      }
      // Clocks and rounding of printed values make starts and ends differ slightly.
      const double tolerance = 1e-6 + 1e-3 * previous.duration_s;
      if (t < previous_end - tolerance) {
        return Status::InvalidInput(where() + "interval starting at t=" + Num(t) +
                                    " overlaps the previous interval, which ends at " +
                                    Num(previous_end));
      }
      interval.gap_before = t > previous_end + tolerance;
    }
    log_.intervals.push_back(std::move(interval));
    return Status::Ok();
  }

  StatusOr<LaserLog> Finish(const std::string& detail) && {
    if (log_.intervals.empty()) {
      return Status::InvalidInput(log_.source + ": holds no records" + detail);
    }
    log_.has_timestamps = has_t_;
    return std::move(log_);
  }

 private:
  LaserLog log_;
  bool has_t_ = false;
};

// ---------------------------------------------------------------------------------------------
// JSON tuples: a hand-written scanner for exactly the subset the published files use.

enum TupleKey { kKeyT, kKeyPhiL, kKeyPhiR, kKeySm, kKeyStart, kNumKeys };
constexpr const char* kTupleKeyNames[kNumKeys] = {"T", "phi_l", "phi_r", "sm", "t"};

class TupleParser {
 public:
  TupleParser(std::string_view text, const std::string& source)
      : p_(text.data()), end_(text.data() + text.size()), builder_(source), source_(source) {
    builder_.Reserve(CountBraces());
  }

  StatusOr<LaserLog> Parse() {
    SkipSpace();
    while (p_ < end_) {
      if (*p_ != '{') {
        const std::string after =
            record_ > 0 ? "after record " + std::to_string(record_) + ": " : "";
        return Status::InvalidInput(Where(source_, line_, 0) + after + "unexpected text '" +
                                    Token() +
                                    "' between records (each record is a { ... } object)");
      }
      LaserInterval interval;
      bool has_t = false;
      CALIB_RETURN_IF_ERROR(ParseRecord(&interval, &has_t));
      CALIB_RETURN_IF_ERROR(builder_.Add(std::move(interval), has_t));
      SkipSpace();
    }
    return std::move(builder_).Finish("");
  }

 private:
  // An exact reserve saves regrowing a large vector; memchr is several times faster than
  // std::count here.
  size_t CountBraces() const {
    size_t count = 0;
    for (const char* q = p_; q < end_; ++count, ++q) {
      q = static_cast<const char*>(std::memchr(q, '{', static_cast<size_t>(end_ - q)));
      if (q == nullptr) break;
    }
    return count;
  }

  void SkipSpace() {
    while (p_ < end_) {
      const char c = *p_;
      if (c == '\n') {
        ++line_;
      } else if (c != ' ' && c != '\t' && c != '\r') {
        break;
      }
      ++p_;
    }
  }

  // A short excerpt of the input at p_ for messages.
  std::string Token() const {
    if (p_ >= end_) return "end of input";
    const char* q = p_;
    while (q < end_ && q - p_ < 24 && !IsJsonSpace(*q) && *q != ',' && *q != '}' && *q != ']' &&
           *q != '{' && *q != ':') {
      ++q;
    }
    if (q == p_) ++q;
    return std::string(p_, q);
  }

  Status Error(const std::string& problem) const {
    return Status::InvalidInput(Where(source_, line_, record_) + problem);
  }
  // Names the line where the record started, which is where a reader looks.
  Status Truncated(const char* inside) const {
    return Status::InvalidInput(Where(source_, record_line_, record_) +
                                "truncated record: the input ends inside " + inside);
  }

  Status ParseNumber(const char* key, double* value) {
    if (p_ >= end_) return Truncated("the record");
    NumberStatus status;
    const char* stop = ScanDouble(p_, end_, value, &status);
    if (status == NumberStatus::kNotNumber ||
        (stop < end_ && !IsJsonSpace(*stop) && *stop != ',' && *stop != '}' && *stop != ']')) {
      return Error(NumberProblem(NumberStatus::kNotNumber, key, Token()));
    }
    if (status != NumberStatus::kOk) return Error(NumberProblem(status, key, Token()));
    p_ = stop;
    return Status::Ok();
  }

  Status ParseSm(Pose2d* sm) {
    if (p_ >= end_) return Truncated("the record");
    if (*p_ != '[') return Error("sm must be an array of 3 numbers, got '" + Token() + "'");
    ++p_;
    SkipSpace();
    if (p_ >= end_) return Truncated("the sm array");
    int count = 0;
    if (*p_ == ']') {
      ++p_;
    } else {
      while (true) {
        double value = 0.0;
        CALIB_RETURN_IF_ERROR(ParseNumber("sm", &value));
        if (count < 3) (*sm)(count) = value;
        ++count;
        SkipSpace();
        if (p_ >= end_) return Truncated("the sm array");
        if (*p_ == ']') {
          ++p_;
          break;
        }
        if (*p_ != ',') return Error("expected ',' or ']' in sm, got '" + Token() + "'");
        ++p_;
        SkipSpace();
        if (p_ >= end_) return Truncated("the sm array");
      }
    }
    if (count != 3) {
      return Error("sm must hold 3 numbers (x, y, theta), got " + std::to_string(count));
    }
    return Status::Ok();
  }

  Status ParseRecord(LaserInterval* interval, bool* has_t) {
    ++record_;
    record_line_ = line_;
    interval->line = line_;
    interval->record = record_;
    ++p_;  // '{'
    bool seen[kNumKeys] = {};
    double values[kNumKeys] = {};
    SkipSpace();
    if (p_ < end_ && *p_ == '}') {
      ++p_;
    } else {
      while (true) {
        SkipSpace();
        if (p_ >= end_) return Truncated("the record");
        if (*p_ != '"') return Error("expected a quoted key, got '" + Token() + "'");
        const char* key_begin = ++p_;
        while (p_ < end_ && *p_ != '"' && *p_ != '\n') ++p_;
        if (p_ >= end_) return Truncated("a key");
        if (*p_ != '"') return Error("unterminated key");
        const std::string_view key(key_begin, static_cast<size_t>(p_ - key_begin));
        ++p_;
        int index = 0;
        while (index < kNumKeys && key != kTupleKeyNames[index]) ++index;
        if (index == kNumKeys) {
          return Error("unknown key \"" + std::string(key) +
                       "\" (expected T, phi_l, phi_r, sm and optionally t)");
        }
        if (seen[index]) return Error("duplicate key \"" + std::string(key) + "\"");
        seen[index] = true;
        SkipSpace();
        if (p_ >= end_) return Truncated("the record");
        if (*p_ != ':') return Error("expected ':' after \"" + std::string(key) + "\"");
        ++p_;
        SkipSpace();
        if (index == kKeySm) {
          CALIB_RETURN_IF_ERROR(ParseSm(&interval->sensor_motion));
        } else {
          if (p_ < end_ && *p_ == '[') {
            return Error(std::string(kTupleKeyNames[index]) + " must be a number, not an array");
          }
          CALIB_RETURN_IF_ERROR(ParseNumber(kTupleKeyNames[index], &values[index]));
        }
        SkipSpace();
        if (p_ >= end_) return Truncated("the record");
        if (*p_ == '}') {
          ++p_;
          break;
        }
        if (*p_ != ',') {
          return Error("expected ',' or '}' after the value of \"" + std::string(key) +
                       "\", got '" + Token() + "'");
        }
        ++p_;
      }
    }
    for (int index = 0; index < kKeyStart; ++index) {
      if (!seen[index]) {
        return Status::InvalidInput(Where(source_, record_line_, record_) + "missing key \"" +
                                    kTupleKeyNames[index] + "\"");
      }
    }
    interval->duration_s = values[kKeyT];
    interval->left_speed = values[kKeyPhiL];
    interval->right_speed = values[kKeyPhiR];
    interval->start_s = values[kKeyStart];
    *has_t = seen[kKeyStart];
    return Status::Ok();
  }

  const char* p_;
  const char* end_;
  LogBuilder builder_;
  const std::string& source_;
  int line_ = 1;
  int record_ = 0;
  int record_line_ = 0;
};

// ---------------------------------------------------------------------------------------------
// The stream files: every column a required number.

struct NumberTable {
  std::vector<double> values;  // Row-major.
  std::vector<int> lines;      // 1-based source line of each row.
};

StatusOr<NumberTable> ReadNumberTable(std::string_view text, const std::string& source,
                                      std::vector<CsvColumn> columns) {
  const size_t width = columns.size();
  CALIB_ASSIGN_OR_RETURN(CsvReader csv, CsvReader::Open(text, source, std::move(columns)));
  NumberTable table;
  while (true) {
    CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
    if (!more) break;
    for (size_t c = 0; c < width; ++c) {
      table.values.push_back(0.0);
      CALIB_RETURN_IF_ERROR(csv.Number(c, &table.values.back()));
    }
    table.lines.push_back(csv.line());
  }
  return table;
}

// ---------------------------------------------------------------------------------------------
// Raw streams.

struct StreamNames {
  std::string source;
  std::string odometry;
  std::string poses;
  const std::vector<int>* odometry_lines = nullptr;  // Source lines, when read from files.
  const std::vector<int>* pose_lines = nullptr;
};

std::string SampleWhere(const std::string& name, const std::vector<int>* lines, size_t k,
                        const char* noun) {
  if (lines != nullptr) return Where(name, (*lines)[k], 0);
  return name + ": " + noun + " " + std::to_string(k + 1) + ": ";
}

// Cumulative wheel angles at time t inside segment [s, s + 1] (or exactly at sample s).
void Interpolate(const std::vector<EncoderSample>& odometry, size_t s, double t, double* left,
                 double* right) {
  const EncoderSample& a = odometry[s];
  if (t == a.t_s || s + 1 >= odometry.size()) {
    *left = a.left_rad;
    *right = a.right_rad;
    return;
  }
  const EncoderSample& b = odometry[s + 1];
  const double fraction = (t - a.t_s) / (b.t_s - a.t_s);
  *left = a.left_rad + (b.left_rad - a.left_rad) * fraction;
  *right = a.right_rad + (b.right_rad - a.right_rad) * fraction;
}

StatusOr<LaserLog> BuildFromStreams(const std::vector<EncoderSample>& odometry,
                                    const std::vector<StampedPose>& poses,
                                    const StreamNames& names) {
  if (odometry.size() < 2) {
    return Status::InvalidInput(names.odometry + ": needs at least 2 odometry samples, got " +
                                std::to_string(odometry.size()));
  }
  for (size_t k = 0; k < odometry.size(); ++k) {
    const EncoderSample& s = odometry[k];
    const auto where = [&] {
      return SampleWhere(names.odometry, names.odometry_lines, k, "sample");
    };
    if (!std::isfinite(s.t_s) || !std::isfinite(s.left_rad) || !std::isfinite(s.right_rad)) {
      return Status::InvalidInput(where() + "values must be finite (NaN or inf found)");
    }
    if (k > 0 && !(s.t_s > odometry[k - 1].t_s)) {
      return Status::InvalidInput(where() + "timestamps must be strictly increasing, got t=" +
                                  Num(s.t_s) + " after " + Num(odometry[k - 1].t_s));
    }
  }
  if (poses.size() < 2) {
    return Status::InvalidInput(names.poses + ": needs at least 2 sensor poses, got " +
                                std::to_string(poses.size()));
  }
  for (size_t k = 0; k < poses.size(); ++k) {
    const StampedPose& p = poses[k];
    const auto where = [&] { return SampleWhere(names.poses, names.pose_lines, k, "pose"); };
    if (!std::isfinite(p.t_s) || !p.world_T_sensor.allFinite()) {
      return Status::InvalidInput(where() + "values must be finite (NaN or inf found)");
    }
    if (k > 0 && !(p.t_s > poses[k - 1].t_s)) {
      return Status::InvalidInput(where() + "timestamps must be strictly increasing, got t=" +
                                  Num(p.t_s) + " after " + Num(poses[k - 1].t_s));
    }
  }

  std::vector<double> periods(odometry.size() - 1);
  for (size_t k = 0; k + 1 < odometry.size(); ++k) {
    periods[k] = odometry[k + 1].t_s - odometry[k].t_s;
  }
  std::nth_element(periods.begin(), periods.begin() + periods.size() / 2, periods.end());
  const double gap_limit = 5.0 * periods[periods.size() / 2];

  // Poses outside the encoder span cannot be integrated: drop those at the ends.
  const double t_begin = odometry.front().t_s;
  const double t_end = odometry.back().t_s;
  size_t first = 0;
  while (first < poses.size() && poses[first].t_s < t_begin) ++first;
  size_t last = poses.size();  // One past the last usable pose.
  while (last > first && poses[last - 1].t_s > t_end) --last;
  if (last < first + 2) {
    return Status::InvalidInput(names.poses +
                                ": no pair of sensor poses lies within the odometry time "
                                "span [" +
                                Num(t_begin) + ", " + Num(t_end) + "] (poses span [" +
                                Num(poses.front().t_s) + ", " + Num(poses.back().t_s) + "])");
  }

  const auto by_time = [](const EncoderSample& s, double t) { return s.t_s < t; };
  LaserLog log;
  log.source = names.source;
  log.has_timestamps = true;
  log.intervals.reserve(last - first - 1);
  bool pending_gap = false;
  for (size_t k = first; k + 1 < last; ++k) {
    const double ta = poses[k].t_s;
    const double tb = poses[k + 1].t_s;
    // j: last sample at or before ta; m: first sample at or after tb. Samples j+1..m-1 lie
    // strictly inside the interval.
    const size_t m = static_cast<size_t>(
        std::lower_bound(odometry.begin(), odometry.end(), tb, by_time) - odometry.begin());
    size_t j = static_cast<size_t>(std::lower_bound(odometry.begin(), odometry.end(), ta, by_time) -
                                   odometry.begin());
    if (odometry[j].t_s > ta) --j;
    bool gap = false;
    for (size_t s = j; s < m && !gap; ++s) {
      gap = odometry[s + 1].t_s - odometry[s].t_s > gap_limit;
    }
    if (gap) {
      // Interpolating across missing encoder data would invent wheel motion.
      pending_gap = true;
      continue;
    }
    LaserInterval interval;
    interval.start_s = ta;
    interval.duration_s = tb - ta;
    interval.sensor_motion = Between(poses[k].world_T_sensor, poses[k + 1].world_T_sensor);
    interval.sensor_motion(2) = WrapAngle(interval.sensor_motion(2));
    interval.gap_before = pending_gap;
    pending_gap = false;
    interval.record = static_cast<int>(k) + 1;
    interval.line = names.pose_lines != nullptr ? (*names.pose_lines)[k] : 0;

    double left_a, right_a, left_b, right_b;
    Interpolate(odometry, j, ta, &left_a, &right_a);
    Interpolate(odometry, odometry[m].t_s == tb ? m : m - 1, tb, &left_b, &right_b);
    interval.left_speed = (left_b - left_a) / interval.duration_s;
    interval.right_speed = (right_b - right_a) / interval.duration_s;
    if (m > j + 1) {
      // Encoder samples inside the interval: keep the speed profile as constant-speed steps.
      interval.steps.reserve(m - j);
      double t_prev = ta, left_prev = left_a, right_prev = right_a;
      for (size_t s = j + 1; s <= m; ++s) {
        const bool at_end = s == m;
        const double t = at_end ? tb : odometry[s].t_s;
        const double left = at_end ? left_b : odometry[s].left_rad;
        const double right = at_end ? right_b : odometry[s].right_rad;
        interval.steps.push_back(WheelStep{t - t_prev, left - left_prev, right - right_prev});
        t_prev = t;
        left_prev = left;
        right_prev = right;
      }
    }
    log.intervals.push_back(std::move(interval));
  }
  if (log.intervals.empty()) {
    return Status::InvalidInput(
        names.source +
        ": no interval remains: every pair of sensor poses spans an encoder "
        "gap longer than 5x the median encoder period (" +
        Num(gap_limit / 5.0) + " s)");
  }
  return log;
}

bool Finite(const LaserInterval& interval) {
  return std::isfinite(interval.start_s) && std::isfinite(interval.duration_s) &&
         std::isfinite(interval.left_speed) && std::isfinite(interval.right_speed) &&
         interval.sensor_motion.allFinite();
}

Status CheckWritable(const LaserLog& log, const std::string& path) {
  for (size_t k = 0; k < log.intervals.size(); ++k) {
    if (!Finite(log.intervals[k])) {
      return Status::InvalidInput(path + ": cannot write interval " + std::to_string(k + 1) +
                                  ": it holds a non-finite value");
    }
  }
  return Status::Ok();
}

}  // namespace

StatusOr<LaserFormat> ParseLaserFormat(const std::string& name) {
  std::string lower = name;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower == "auto") return LaserFormat::kAuto;
  if (lower == "tuples" || lower == "json") return LaserFormat::kTuples;
  if (lower == "csv") return LaserFormat::kCsv;
  if (lower == "stream") return LaserFormat::kStream;
  return Status::InvalidInput("unknown laser log format '" + name +
                              "'; accepted: auto, tuples, json, csv, stream");
}

StatusOr<LaserLog> ParseLaserTuples(const std::string& text, const std::string& source) {
  return TupleParser(WithoutBom(text), source).Parse();
}

StatusOr<LaserLog> ParseLaserCsv(const std::string& text, const std::string& source) {
  enum { kT, kPhiL, kPhiR, kSmX, kSmY, kSmTheta, kStart };
  CALIB_ASSIGN_OR_RETURN(CsvReader csv, CsvReader::Open(text, source,
                                                        {{"T"},
                                                         {"phi_l"},
                                                         {"phi_r"},
                                                         {"sm_x"},
                                                         {"sm_y"},
                                                         {"sm_theta"},
                                                         {"t", /*required=*/false}}));
  LogBuilder builder(source);
  while (true) {
    CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
    if (!more) break;
    double v[kStart + 1] = {};
    for (int c = kT; c < kStart; ++c) CALIB_RETURN_IF_ERROR(csv.Number(c, &v[c]));
    bool has_t = false;
    CALIB_RETURN_IF_ERROR(csv.Number(kStart, &v[kStart], &has_t));
    LaserInterval interval;
    interval.duration_s = v[kT];
    interval.left_speed = v[kPhiL];
    interval.right_speed = v[kPhiR];
    interval.sensor_motion = Pose2d(v[kSmX], v[kSmY], v[kSmTheta]);
    interval.start_s = v[kStart];
    interval.line = csv.line();
    interval.record = csv.record();
    CALIB_RETURN_IF_ERROR(builder.Add(std::move(interval), has_t));
  }
  return std::move(builder).Finish(" (only a header)");
}

StatusOr<LaserLog> ReadLaserLog(const std::string& path, LaserFormat format) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return Status::Io(path + ": no such file or directory");
  const bool directory = fs::is_directory(status);
  if (format == LaserFormat::kStream || (format == LaserFormat::kAuto && directory)) {
    if (!directory) {
      return Status::InvalidInput(path +
                                  ": the stream format reads a directory holding odometry.csv "
                                  "and sensor_poses.csv, but this is a file");
    }
    return ReadLaserStream(path);
  }
  std::string text;
  CALIB_RETURN_IF_ERROR(ReadWholeFile(path, &text));
  if (format == LaserFormat::kAuto) {
    const std::string_view body = WithoutBom(text);
    size_t i = 0;
    while (i < body.size() && IsJsonSpace(body[i])) ++i;
    format = i < body.size() && body[i] == '{' ? LaserFormat::kTuples : LaserFormat::kCsv;
  }
  return format == LaserFormat::kTuples ? ParseLaserTuples(text, path) : ParseLaserCsv(text, path);
}

StatusOr<LaserLog> LaserLogFromStreams(const std::vector<EncoderSample>& odometry,
                                       const std::vector<StampedPose>& sensor_poses,
                                       const std::string& source) {
  StreamNames names;
  names.source = source;
  names.odometry = source + " (odometry)";
  names.poses = source + " (sensor poses)";
  return BuildFromStreams(odometry, sensor_poses, names);
}

StatusOr<LaserLog> ReadLaserStream(const std::string& directory) {
  std::error_code ec;
  if (!fs::is_directory(directory, ec)) {
    return Status::Io(directory +
                      ": not a directory (the stream format reads a directory "
                      "holding odometry.csv and sensor_poses.csv)");
  }
  const std::string odometry_path = (fs::path(directory) / "odometry.csv").string();
  const std::string poses_path = (fs::path(directory) / "sensor_poses.csv").string();

  std::string text;
  CALIB_RETURN_IF_ERROR(ReadWholeFile(odometry_path, &text));
  CALIB_ASSIGN_OR_RETURN(const NumberTable odometry_table,
                         ReadNumberTable(text, odometry_path, {{"t"}, {"left"}, {"right"}}));
  std::vector<EncoderSample> odometry(odometry_table.lines.size());
  for (size_t k = 0; k < odometry.size(); ++k) {
    const double* v = &odometry_table.values[3 * k];
    odometry[k] = EncoderSample{v[0], v[1], v[2], odometry_table.lines[k]};
  }

  CALIB_RETURN_IF_ERROR(ReadWholeFile(poses_path, &text));
  CALIB_ASSIGN_OR_RETURN(const NumberTable pose_table,
                         ReadNumberTable(text, poses_path, {{"t"}, {"x"}, {"y"}, {"theta"}}));
  std::vector<StampedPose> poses(pose_table.lines.size());
  for (size_t k = 0; k < poses.size(); ++k) {
    const double* v = &pose_table.values[4 * k];
    poses[k].t_s = v[0];
    poses[k].world_T_sensor = Pose2d(v[1], v[2], v[3]);
  }

  StreamNames names;
  names.source = directory;
  names.odometry = odometry_path;
  names.poses = poses_path;
  names.odometry_lines = &odometry_table.lines;
  names.pose_lines = &pose_table.lines;
  return BuildFromStreams(odometry, poses, names);
}

Status WriteLaserTuples(const LaserLog& log, const std::string& path) {
  CALIB_RETURN_IF_ERROR(CheckWritable(log, path));
  std::string out;
  out.reserve(log.intervals.size() * 160);
  for (const LaserInterval& interval : log.intervals) {
    out += "{ ";
    if (log.has_timestamps) {
      out += "\"t\": ";
      AppendScientific(&out, interval.start_s);
      out += ", ";
    }
    out += "\"T\": ";
    AppendScientific(&out, interval.duration_s);
    out += ", \"phi_l\": ";
    AppendScientific(&out, interval.left_speed);
    out += ", \"phi_r\": ";
    AppendScientific(&out, interval.right_speed);
    out += ", \"sm\": [ ";
    AppendScientific(&out, interval.sensor_motion(0));
    out += ", ";
    AppendScientific(&out, interval.sensor_motion(1));
    out += ", ";
    AppendScientific(&out, interval.sensor_motion(2));
    out += " ] }\n";
  }
  return WriteWholeFile(path, out);
}

Status WriteLaserCsv(const LaserLog& log, const std::string& path) {
  CALIB_RETURN_IF_ERROR(CheckWritable(log, path));
  std::string out = "t,T,phi_l,phi_r,sm_x,sm_y,sm_theta\n";
  out.reserve(log.intervals.size() * 120 + out.size());
  for (const LaserInterval& interval : log.intervals) {
    const double values[7] = {interval.start_s,          interval.duration_s,
                              interval.left_speed,       interval.right_speed,
                              interval.sensor_motion(0), interval.sensor_motion(1),
                              interval.sensor_motion(2)};
    for (int i = 0; i < 7; ++i) {
      if (i > 0) out += ',';
      AppendGeneral(&out, values[i]);
    }
    out += '\n';
  }
  return WriteWholeFile(path, out);
}

Status WriteLaserStream(const std::vector<EncoderSample>& odometry,
                        const std::vector<StampedPose>& sensor_poses,
                        const std::string& directory) {
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) return Status::Io(directory + ": cannot create the directory: " + ec.message());
  std::string out = "t,left,right\n";
  for (size_t k = 0; k < odometry.size(); ++k) {
    const EncoderSample& s = odometry[k];
    if (!std::isfinite(s.t_s) || !std::isfinite(s.left_rad) || !std::isfinite(s.right_rad)) {
      return Status::InvalidInput(directory + ": cannot write odometry sample " +
                                  std::to_string(k + 1) + ": it holds a non-finite value");
    }
    AppendGeneral(&out, s.t_s);
    out += ',';
    AppendGeneral(&out, s.left_rad);
    out += ',';
    AppendGeneral(&out, s.right_rad);
    out += '\n';
  }
  CALIB_RETURN_IF_ERROR(WriteWholeFile((fs::path(directory) / "odometry.csv").string(), out));
  out = "t,x,y,theta\n";
  for (size_t k = 0; k < sensor_poses.size(); ++k) {
    const StampedPose& p = sensor_poses[k];
    if (!std::isfinite(p.t_s) || !p.world_T_sensor.allFinite()) {
      return Status::InvalidInput(directory + ": cannot write sensor pose " +
                                  std::to_string(k + 1) + ": it holds a non-finite value");
    }
    AppendGeneral(&out, p.t_s);
    for (int i = 0; i < 3; ++i) {
      out += ',';
      AppendGeneral(&out, p.world_T_sensor(i));
    }
    out += '\n';
  }
  return WriteWholeFile((fs::path(directory) / "sensor_poses.csv").string(), out);
}

}  // namespace calib
