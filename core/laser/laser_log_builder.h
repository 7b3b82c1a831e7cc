#ifndef CALIB_CORE_LASER_LASER_LOG_BUILDER_H_
#define CALIB_CORE_LASER_LASER_LOG_BUILDER_H_

#include <calib/core/huge_pages.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/status.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

// Pieces the laser readers and writers share (not part of the API).
namespace calib {
namespace laser_io_internal {

inline bool IsJsonSpace(char c) { return c == ' ' || c == '\n' || c == '\t' || c == '\r'; }

// "source:line: record n: " with the parts that are known.
inline std::string Where(const std::string& source, int64_t line, int64_t record) {
  std::string where = source;
  if (line > 0) where += ":" + std::to_string(line);
  where += ": ";
  if (record > 0) where += "record " + std::to_string(record) + ": ";
  return where;
}

// ---------------------------------------------------------------------------------------------
// Checks shared by the tuple and CSV readers: T, the optional t, and the time line.

class LogBuilder {
 public:
  explicit LogBuilder(const std::string& source) { log_.source = source; }
  // An estimate (EstimateByteCount): when it asks for more memory than there is, the records
  // grow as they come instead. A long log's records go on 2 MB pages (huge_pages.h).
  void Reserve(size_t n) { ReserveOnHugePages(&log_.intervals, n); }
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
    if (IsExactDuplicate(previous, interval, has_t)) {
      duplicates_.push_back(interval.record);
      return Status::Ok();
    }
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
      if (t < previous_end - tolerance && IsDurationGlitch(previous, t)) {
        // The stamps say where the previous interval ends: its T is a glitch, not an overlap.
        if (duration_glitches_.empty()) duration_glitch_ = DurationGlitch(previous, t);
        duration_glitches_.push_back(previous.record);
        log_.intervals.pop_back();
        interval.gap_before = true;
        log_.intervals.push_back(std::move(interval));
        return Status::Ok();
      }
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
    if (!duplicates_.empty()) log_.warnings.push_back(DuplicatesWarning());
    if (!duration_glitches_.empty()) {
      const size_t total = log_.intervals.size() + duration_glitches_.size();
      // Many such records are no glitch: T is not the interval's length in seconds.
      if (duration_glitches_.size() > std::max<size_t>(2, total / 50)) {
        return Status::InvalidInput(
            log_.source + ": " + std::to_string(duration_glitches_.size()) + " of " +
            std::to_string(total) + " records have a T longer than the time to the next " +
            "record's t (first: " + duration_glitch_ +
            "): T must be each interval's length in seconds, on the clock of t");
      }
      log_.warnings.push_back(log_.source + ": " + std::to_string(duration_glitches_.size()) +
                              " record(s) dropped for a T longer than the time to the next " +
                              "record's t (first: " + duration_glitch_ + ")");
    }
    return std::move(log_);
  }

 private:
  // The same record written twice: every value equal (t too when given). Without t, a still
  // robot may log equal records, so only records with motion count.
  static bool IsExactDuplicate(const LaserInterval& a, const LaserInterval& b, bool has_t) {
    const bool moves =
        b.left_speed != 0.0 || b.right_speed != 0.0 || b.sensor_motion != Pose2d::Zero();
    return (has_t ? a.start_s == b.start_s : moves) && a.duration_s == b.duration_s &&
           a.left_speed == b.left_speed && a.right_speed == b.right_speed &&
           a.sensor_motion == b.sensor_motion;
  }

  // A T at least twice the time to the next record's start (the next starting after this one).
  static bool IsDurationGlitch(const LaserInterval& previous, double t) {
    return t > previous.start_s && previous.duration_s > 2.0 * (t - previous.start_s);
  }
  std::string DurationGlitch(const LaserInterval& previous, double t) const {
    return Where(log_.source, previous.line, previous.record) + "T = " + Num(previous.duration_s) +
           " s, but the next record starts " + Num(t - previous.start_s) + " s after it";
  }

  std::string DuplicatesWarning() const {
    std::string records;
    for (size_t i = 0; i < duplicates_.size() && i < 5; ++i) {
      records += (i > 0 ? ", " : "") + std::to_string(duplicates_[i]);
    }
    if (duplicates_.size() > 5) records += ", ...";
    return log_.source + ": " + std::to_string(duplicates_.size()) +
           " exact duplicate record(s) dropped (record " + records +
           " repeats the record before it)";
  }

  LaserLog log_;
  bool has_t_ = false;
  std::vector<int> duplicates_;         // Records dropped as exact duplicates.
  std::vector<int> duration_glitches_;  // Records dropped for a T the stamps contradict.
  std::string duration_glitch_;         // The first of them, in words.
};

inline bool Finite(const LaserInterval& interval) {
  return std::isfinite(interval.start_s) && std::isfinite(interval.duration_s) &&
         std::isfinite(interval.left_speed) && std::isfinite(interval.right_speed) &&
         interval.sensor_motion.allFinite();
}

inline Status CheckWritable(const LaserLog& log, const std::string& path) {
  for (size_t k = 0; k < log.intervals.size(); ++k) {
    if (!Finite(log.intervals[k])) {
      return Status::InvalidInput(path + ": cannot write interval " + std::to_string(k + 1) +
                                  ": it holds a non-finite value");
    }
  }
  return Status::Ok();
}

}  // namespace laser_io_internal
}  // namespace calib

#endif  // CALIB_CORE_LASER_LASER_LOG_BUILDER_H_
