#include <calib/core/csv.h>
#include <calib/core/encoder_spikes.h>
#include <calib/core/laser/laser_log_builder.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_plausibility.h>
#include <calib/core/laser/wheel_readings.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>
#include <calib/core/timing/stamp_timing.h>
#include <calib/core/timing/wheel_angle_spline.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace calib {
namespace {

using laser_io_internal::Where;

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// The stream files: every column a required number.

// Reads a stream file into records (stamp, values, line) in file order.
StatusOr<StreamRecords> ReadRecords(std::string_view text, const std::string& source,
                                    std::vector<std::string> value_names) {
  std::vector<CsvColumn> columns = {{"t"}};
  for (const std::string& name : value_names) columns.push_back({name.c_str()});
  const size_t width = value_names.size();
  CALIB_ASSIGN_OR_RETURN(CsvReader csv, CsvReader::Open(text, source, std::move(columns)));
  StreamRecords records;
  while (true) {
    CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
    if (!more) break;
    records.stamps_s.push_back(0.0);
    CALIB_RETURN_IF_ERROR(csv.Number(0, &records.stamps_s.back()));
    for (size_t c = 0; c < width; ++c) {
      records.values.push_back(0.0);
      CALIB_RETURN_IF_ERROR(csv.Number(c + 1, &records.values.back()));
    }
    records.lines.push_back(SaturatedInt(csv.line()));
  }
  records.value_names = std::move(value_names);
  return records;
}

// ---------------------------------------------------------------------------------------------
// Raw streams.

struct StreamNames {
  std::string source;
  std::string odometry;
  std::string poses;
};

// "file:line: " for a sample read from a file, else "name: sample k: ".
std::string SampleWhere(const std::string& name, int line, size_t k, const char* noun) {
  if (line > 0) return Where(name, line, 0);
  return name + ": " + noun + " " + std::to_string(k + 1) + ": ";
}

StreamRecords OdometryRecords(const std::vector<EncoderSample>& odometry) {
  StreamRecords records;
  records.value_names = {"left", "right"};
  for (const EncoderSample& s : odometry) {
    records.stamps_s.push_back(s.t_s);
    records.values.insert(records.values.end(), {s.left_rad, s.right_rad});
    records.lines.push_back(s.line);
  }
  return records;
}

StreamRecords PoseRecords(const std::vector<StampedPose>& poses) {
  StreamRecords records;
  records.value_names = {"x", "y", "theta"};
  for (const StampedPose& p : poses) {
    records.stamps_s.push_back(p.t_s);
    const Pose2d& v = p.world_T_sensor;
    records.values.insert(records.values.end(), {v(0), v(1), v(2)});
    records.lines.push_back(p.line);
  }
  return records;
}

// Lines are named in messages only when every record has one.
void DropUnknownLines(StreamRecords* records) {
  if (std::count(records->lines.begin(), records->lines.end(), 0) > 0) records->lines.clear();
}

// " (line 12)" when the line is known.
std::string LineNote(int line) {
  return line > 0 ? " (line " + std::to_string(line) + ")" : std::string();
}

Status ValidateOdometry(const std::vector<EncoderSample>& odometry, const StreamNames& names) {
  if (odometry.size() < 2) {
    return Status::InvalidInput(names.odometry + ": needs at least 2 odometry samples, got " +
                                std::to_string(odometry.size()));
  }
  for (size_t k = 0; k < odometry.size(); ++k) {
    const EncoderSample& s = odometry[k];
    const auto where = [&] { return SampleWhere(names.odometry, s.line, k, "sample"); };
    if (!std::isfinite(s.t_s) || !std::isfinite(s.left_rad) || !std::isfinite(s.right_rad)) {
      return Status::InvalidInput(where() + "values must be finite (NaN or inf found)");
    }
    if (k > 0 && !(s.t_s > odometry[k - 1].t_s)) {
      return Status::InvalidInput(
          where() + "timestamps must be strictly increasing, got t=" + Num(s.t_s) + " after " +
          Num(odometry[k - 1].t_s) + LineNote(odometry[k - 1].line));
    }
  }
  return Status::Ok();
}

Status ValidatePoses(const std::vector<StampedPose>& poses, const StreamNames& names) {
  if (poses.size() < 2) {
    return Status::InvalidInput(names.poses + ": needs at least 2 sensor poses, got " +
                                std::to_string(poses.size()));
  }
  for (size_t k = 0; k < poses.size(); ++k) {
    const StampedPose& p = poses[k];
    const auto where = [&] { return SampleWhere(names.poses, p.line, k, "pose"); };
    if (!std::isfinite(p.t_s) || !p.world_T_sensor.allFinite()) {
      return Status::InvalidInput(where() + "values must be finite (NaN or inf found)");
    }
    if (k > 0 && !(p.t_s > poses[k - 1].t_s)) {
      return Status::InvalidInput(where() +
                                  "timestamps must be strictly increasing, got t=" + Num(p.t_s) +
                                  " after " + Num(poses[k - 1].t_s) + LineNote(poses[k - 1].line));
    }
  }
  return Status::Ok();
}

// Five times the median encoder period: a longer step between samples is missing data.
double EncoderGapLimit(const std::vector<EncoderSample>& odometry) {
  std::vector<double> periods(odometry.size() - 1);
  for (size_t k = 0; k + 1 < odometry.size(); ++k) {
    periods[k] = odometry[k + 1].t_s - odometry[k].t_s;
  }
  std::nth_element(periods.begin(), periods.begin() + periods.size() / 2, periods.end());
  return 5.0 * periods[periods.size() / 2];
}

// Poses outside the encoder span cannot be integrated: [*first, *last) are those within it, after
// dropping those at the ends.
Status UsablePoses(const std::vector<EncoderSample>& odometry,
                   const std::vector<StampedPose>& poses, const StreamNames& names, size_t* first,
                   size_t* last) {
  const double t_begin = odometry.front().t_s;
  const double t_end = odometry.back().t_s;
  *first = 0;
  while (*first < poses.size() && poses[*first].t_s < t_begin) ++*first;
  *last = poses.size();  // One past the last usable pose.
  while (*last > *first && poses[*last - 1].t_s > t_end) --*last;
  if (*last < *first + 2) {
    return Status::InvalidInput(names.poses +
                                ": no pair of sensor poses lies within the odometry time "
                                "span [" +
                                Num(t_begin) + ", " + Num(t_end) + "] (poses span [" +
                                Num(poses.front().t_s) + ", " + Num(poses.back().t_s) + "])");
  }
  return Status::Ok();
}

// The wheel motion over [ta, tb], where j is the last sample at or before ta and m the first at or
// after tb (samples j+1..m-1 lie strictly inside): mean speeds, and constant-speed steps when
// samples lie inside. The angles at ta and tb lie on the cubic between polls or on the line.
void SetWheelMotion(const std::vector<EncoderSample>& odometry, size_t j, size_t m, double ta,
                    double tb, bool cubic, LaserInterval* interval) {
  double left_a, right_a, left_b, right_b;
  WheelAnglesInSegment(odometry, j, ta, cubic, &left_a, &right_a);
  WheelAnglesInSegment(odometry, odometry[m].t_s == tb ? m : m - 1, tb, cubic, &left_b, &right_b);
  interval->left_speed = (left_b - left_a) / interval->duration_s;
  interval->right_speed = (right_b - right_a) / interval->duration_s;
  if (m > j + 1) {
    // Encoder samples inside the interval: keep the speed profile as constant-speed steps.
    interval->steps.reserve(m - j);
    double t_prev = ta, left_prev = left_a, right_prev = right_a;
    for (size_t s = j + 1; s <= m; ++s) {
      const bool at_end = s == m;
      const double t = at_end ? tb : odometry[s].t_s;
      const double left = at_end ? left_b : odometry[s].left_rad;
      const double right = at_end ? right_b : odometry[s].right_rad;
      interval->steps.push_back(WheelStep{t - t_prev, left - left_prev, right - right_prev});
      t_prev = t;
      left_prev = left;
      right_prev = right;
    }
  }
}

StreamNames DirectoryNames(const std::string& directory) {
  return StreamNames{directory, (fs::path(directory) / "odometry.csv").string(),
                     (fs::path(directory) / "sensor_poses.csv").string()};
}

// Drops exact duplicates (an error for a repeated stamp with other values), validates, and
// appends the timing of each stream as given to `timing` (may be null).
// Wrapped wheel angles are unwrapped first, and both corrections are told in `warnings` (may be
// null).
StatusOr<LaserStreams> PrepareStreams(StreamRecords odometry, StreamRecords poses,
                                      const StreamNames& names, std::vector<StreamTiming>* timing,
                                      std::vector<std::string>* warnings,
                                      const std::vector<int>& segments = {}) {
  CALIB_RETURN_IF_ERROR(CheckStampUnit(odometry.stamps_s, names.odometry));
  CALIB_RETURN_IF_ERROR(CheckStampUnit(poses.stamps_s, names.poses));
  const std::vector<double> given_stamps = poses.stamps_s;
  const int turns =
      UnwrapWheelAngles(&odometry.values, 2, 0) + UnwrapWheelAngles(&odometry.values, 2, 1);
  if (turns > 0 && warnings != nullptr) {
    warnings->push_back(names.odometry +
                        ": the wheel angles were wrapped to one turn (the format wants "
                        "cumulative angles): " +
                        std::to_string(turns) + " jumps of 2π were unwrapped");
  }
  if (timing != nullptr) {
    // The records as given: the analysis counts the duplicates itself.
    timing->push_back(
        AnalyzeStreamTiming(odometry.stamps_s, odometry.values, "odometry", names.odometry));
    timing->push_back(
        AnalyzeStreamTiming(poses.stamps_s, poses.values, "sensor_poses", names.poses));
  }
  DropUnknownLines(&odometry);
  DropUnknownLines(&poses);
  int dropped[2] = {0, 0};
  CALIB_RETURN_IF_ERROR(DropExactDuplicates(names.odometry, &odometry, &dropped[0]));
  CALIB_RETURN_IF_ERROR(DropExactDuplicates(names.poses, &poses, &dropped[1]));
  for (int i = 0; i < 2; ++i) {
    if (dropped[i] == 0 || warnings == nullptr) continue;
    warnings->push_back((i == 0 ? names.odometry : names.poses) + ": " +
                        std::to_string(dropped[i]) +
                        " exact duplicate record(s) dropped (same stamp and values as the "
                        "record before)");
  }
  LaserStreams streams;
  for (size_t k = 0; k < odometry.stamps_s.size(); ++k) {
    const double* v = &odometry.values[2 * k];
    const int line = odometry.lines.empty() ? 0 : odometry.lines[k];
    streams.odometry.push_back(EncoderSample{odometry.stamps_s[k], v[0], v[1], line});
  }
  for (size_t k = 0, given = 0; k < poses.stamps_s.size(); ++k) {
    const double* v = &poses.values[3 * k];
    const int line = poses.lines.empty() ? 0 : poses.lines[k];
    // The duplicates dropped kept the order: the given pose with this stamp has the segment.
    while (given + 1 < segments.size() && given_stamps[given] != poses.stamps_s[k]) ++given;
    const int segment = given < segments.size() ? segments[given] : 0;
    streams.sensor_poses.push_back(
        StampedPose{poses.stamps_s[k], Pose2d(v[0], v[1], v[2]), line, segment});
  }
  int first_line = 0;
  if (const int spikes = DropEncoderSpikes(&streams.odometry, &first_line);
      spikes > 0 && warnings != nullptr) {
    warnings->push_back(names.odometry + ": " + std::to_string(spikes) +
                        " encoder sample(s) dropped: the wheel angle jumps away and back, a "
                        "logging glitch (first" +
                        (first_line > 0 ? " at line " + std::to_string(first_line) : "") + ")");
  }
  CALIB_RETURN_IF_ERROR(ValidateOdometry(streams.odometry, names));
  CALIB_RETURN_IF_ERROR(ValidatePoses(streams.sensor_poses, names));
  return streams;
}

StatusOr<LaserLog> BuildFromStreams(const std::vector<EncoderSample>& odometry,
                                    const std::vector<StampedPose>& poses,
                                    const StreamNames& names) {
  const double gap_limit = EncoderGapLimit(odometry);
  size_t first = 0;
  size_t last = 0;
  CALIB_RETURN_IF_ERROR(UsablePoses(odometry, poses, names, &first, &last));
  const bool cubic = CubicBetweenPolls(gap_limit / 5.0);

  const auto by_time = [](const EncoderSample& s, double t) { return s.t_s < t; };
  // A pose equal to the one before is a held repeat (the logger picked up the same sample again,
  // stamped later) or a sensor at rest: the interval runs on to the next distinct pose, as the
  // timing's samples do (core/timing/stream_samples.h). Held repeats as intervals of their own
  // had no motion over a pick-up period of turning wheels, which fast turns made look like a
  // wheel of the wrong sign.
  std::vector<size_t> distinct;
  for (size_t k = first; k < last; ++k) {
    if (distinct.empty() || poses[k].world_T_sensor != poses[distinct.back()].world_T_sensor) {
      distinct.push_back(k);
    }
  }
  if (distinct.size() < 2) {
    return Status::InvalidInput(names.poses +
                                ": every sensor pose within the odometry time span "
                                "is the same: the sensor never moved");
  }
  LaserLog log;
  log.source = names.source;
  log.has_timestamps = true;
  log.intervals.reserve(distinct.size() - 1);
  bool pending_gap = false;
  for (size_t i = 0; i + 1 < distinct.size(); ++i) {
    const size_t k = distinct[i], next = distinct[i + 1];
    const double ta = poses[k].t_s;
    const double tb = poses[next].t_s;
    // j: last sample at or before ta; m: first sample at or after tb. Samples j+1..m-1 lie
    // strictly inside the interval.
    const size_t m = static_cast<size_t>(
        std::lower_bound(odometry.begin(), odometry.end(), tb, by_time) - odometry.begin());
    size_t j = static_cast<size_t>(std::lower_bound(odometry.begin(), odometry.end(), ta, by_time) -
                                   odometry.begin());
    if (odometry[j].t_s > ta) --j;
    bool gap = poses[k].segment != poses[next].segment;
    for (size_t s = j; s < m && !gap; ++s) {
      gap = odometry[s + 1].t_s - odometry[s].t_s > gap_limit;
    }
    if (gap) {
      // Interpolating across missing encoder data would invent wheel motion; poses of two
      // segments have no measured displacement between them.
      pending_gap = true;
      continue;
    }
    LaserInterval interval;
    interval.start_s = ta;
    interval.duration_s = tb - ta;
    interval.sensor_motion = Between(poses[k].world_T_sensor, poses[next].world_T_sensor);
    interval.sensor_motion(2) = WrapAngle(interval.sensor_motion(2));
    interval.gap_before = pending_gap;
    pending_gap = false;
    interval.record = static_cast<int>(k) + 1;
    interval.line = poses[k].line;
    SetWheelMotion(odometry, j, m, ta, tb, cubic, &interval);
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

// One CSV row of shortest round-trip numbers.
void AppendCsvRow(std::string* out, std::initializer_list<double> values) {
  const char* separator = "";
  for (const double value : values) {
    *out += separator;
    AppendGeneral(out, value);
    separator = ",";
  }
  *out += '\n';
}

// The log of the streams read (their timing and the readers' warnings kept).
StatusOr<LaserLog> LogOfStreams(const StreamNames& names,
                                const std::function<StatusOr<LaserStreams>(
                                    std::vector<StreamTiming>*, std::vector<std::string>*)>& read) {
  std::vector<StreamTiming> timing;
  std::vector<std::string> warnings;
  CALIB_ASSIGN_OR_RETURN(LaserStreams streams, read(&timing, &warnings));
  CALIB_ASSIGN_OR_RETURN(LaserLog log,
                         BuildFromStreams(streams.odometry, streams.sensor_poses, names));
  log.streams = std::move(streams);
  log.stream_timing = std::move(timing);
  log.warnings = std::move(warnings);
  DropImplausibleIntervals(&log);
  return log;
}

}  // namespace

StatusOr<LaserLog> LaserLogFromStreams(const std::vector<EncoderSample>& odometry,
                                       const std::vector<StampedPose>& sensor_poses,
                                       const std::string& source) {
  return LaserLogFromStreams(odometry, sensor_poses, source, source + " (odometry)",
                             source + " (sensor poses)");
}

StatusOr<LaserLog> LaserLogFromStreams(const std::vector<EncoderSample>& odometry,
                                       const std::vector<StampedPose>& sensor_poses,
                                       const std::string& source, const std::string& odometry_name,
                                       const std::string& poses_name) {
  const StreamNames names{source, odometry_name, poses_name};
  std::vector<int> segments;
  for (const StampedPose& p : sensor_poses) segments.push_back(p.segment);
  return GuardAllocation(source, [&] {
    return LogOfStreams(
        names, [&](std::vector<StreamTiming>* timing, std::vector<std::string>* warnings) {
          return PrepareStreams(OdometryRecords(odometry), PoseRecords(sensor_poses), names, timing,
                                warnings, segments);
        });
  });
}

namespace {

StatusOr<LaserStreams> ParseStreamSamples(std::string_view odometry_text,
                                          std::string_view poses_text, const StreamNames& names,
                                          std::vector<StreamTiming>* timing,
                                          std::vector<std::string>* warnings) {
  CALIB_ASSIGN_OR_RETURN(StreamRecords odometry,
                         ReadRecords(odometry_text, names.odometry, {"left", "right"}));
  CALIB_ASSIGN_OR_RETURN(StreamRecords poses,
                         ReadRecords(poses_text, names.poses, {"x", "y", "theta"}));
  return PrepareStreams(std::move(odometry), std::move(poses), names, timing, warnings);
}

StatusOr<LaserStreams> ReadStreamSamples(const std::string& directory,
                                         std::vector<StreamTiming>* timing,
                                         std::vector<std::string>* warnings) {
  std::error_code ec;
  if (!fs::is_directory(directory, ec)) {
    return Status::Io(directory +
                      ": not a directory (the stream format reads a directory "
                      "holding odometry.csv and sensor_poses.csv)");
  }
  const StreamNames names = DirectoryNames(directory);
  return GuardAllocation(directory, [&]() -> StatusOr<LaserStreams> {
    CALIB_ASSIGN_OR_RETURN(const MappedFile odometry_file, MappedFile::OpenText(names.odometry));
    CALIB_ASSIGN_OR_RETURN(StreamRecords odometry,
                           ReadRecords(odometry_file.text(), names.odometry, {"left", "right"}));
    CALIB_ASSIGN_OR_RETURN(const MappedFile poses_file, MappedFile::OpenText(names.poses));
    CALIB_ASSIGN_OR_RETURN(StreamRecords poses,
                           ReadRecords(poses_file.text(), names.poses, {"x", "y", "theta"}));
    return PrepareStreams(std::move(odometry), std::move(poses), names, timing, warnings);
  });
}

}  // namespace

StatusOr<LaserStreams> ReadLaserStreamSamples(const std::string& directory,
                                              std::vector<StreamTiming>* timing) {
  return ReadStreamSamples(directory, timing, nullptr);
}

StatusOr<std::vector<EncoderSample>> ReadOdometryCsv(const std::string& path) {
  CALIB_ASSIGN_OR_RETURN(const MappedFile file, MappedFile::OpenText(path));
  return GuardAllocation(path, [&]() -> StatusOr<std::vector<EncoderSample>> {
    CALIB_ASSIGN_OR_RETURN(const StreamRecords records,
                           ReadRecords(file.text(), path, {"left", "right"}));
    std::vector<EncoderSample> samples;
    for (size_t k = 0; k < records.stamps_s.size(); ++k) {
      const int line = records.lines.empty() ? 0 : records.lines[k];
      samples.push_back(EncoderSample{records.stamps_s[k], records.values[2 * k],
                                      records.values[2 * k + 1], line});
    }
    return samples;
  });
}

StatusOr<LaserLog> ReadLaserStream(const std::string& directory) {
  const StreamNames names = DirectoryNames(directory);
  return GuardAllocation(directory, [&] {
    return LogOfStreams(names,
                        [&](std::vector<StreamTiming>* timing, std::vector<std::string>* warnings) {
                          return ReadStreamSamples(directory, timing, warnings);
                        });
  });
}

StatusOr<LaserLog> ParseLaserStream(std::string_view odometry_csv,
                                    std::string_view sensor_poses_csv,
                                    const std::string& directory) {
  const StreamNames names = DirectoryNames(directory);
  return GuardAllocation(directory, [&] {
    return LogOfStreams(
        names, [&](std::vector<StreamTiming>* timing, std::vector<std::string>* warnings) {
          return ParseStreamSamples(odometry_csv, sensor_poses_csv, names, timing, warnings);
        });
  });
}

StatusOr<LaserLog> ShiftSensorStamps(LaserLog log, double offset_s) {
  if (log.streams.sensor_poses.empty()) {
    return Status::InvalidInput(log.source +
                                ": a time offset applies to sample stamps, and this log holds "
                                "intervals (tuples or CSV) without them; give the raw streams");
  }
  if (!std::isfinite(offset_s)) return Status::InvalidInput("the time offset is not finite");
  for (StampedPose& pose : log.streams.sensor_poses) pose.t_s += offset_s;
  CALIB_ASSIGN_OR_RETURN(
      LaserLog shifted,
      BuildFromStreams(log.streams.odometry, log.streams.sensor_poses, DirectoryNames(log.source)));
  shifted.streams = std::move(log.streams);
  shifted.stream_timing = std::move(log.stream_timing);
  shifted.warnings = std::move(log.warnings);
  return shifted;
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
    AppendCsvRow(&out, {s.t_s, s.left_rad, s.right_rad});
  }
  CALIB_RETURN_IF_ERROR(WriteWholeFile((fs::path(directory) / "odometry.csv").string(), out));
  out = "t,x,y,theta\n";
  for (size_t k = 0; k < sensor_poses.size(); ++k) {
    const StampedPose& p = sensor_poses[k];
    if (!std::isfinite(p.t_s) || !p.world_T_sensor.allFinite()) {
      return Status::InvalidInput(directory + ": cannot write sensor pose " +
                                  std::to_string(k + 1) + ": it holds a non-finite value");
    }
    AppendCsvRow(&out, {p.t_s, p.world_T_sensor(0), p.world_T_sensor(1), p.world_T_sensor(2)});
  }
  return WriteWholeFile((fs::path(directory) / "sensor_poses.csv").string(), out);
}

}  // namespace calib
