#include <calib/core/laser/laser_log_io.h>
#include <calib/core/order_statistic.h>
#include <calib/core/se2.h>
#include <calib/core/text_format.h>
#include <calib/core/text_number.h>
#include <calib/core/timing/stamp_timing.h>
#include <calib/solvers/scan_matching/nominal_motion.h>
#include <calib/solvers/scan_matching/scan_laser_log.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <future>
#include <map>
#include <set>

namespace calib {
namespace {

// The nominal wheels and mounting of the options.
WheelsAndMounting Nominal(const ScanLogOptions& o) { return {o.nominal, o.nominal_base_T_sensor}; }

// "12 of 1800 scan matches failed (degenerate 10, too few correspondences 2)".
std::string FailureSummary(const ScanOdometryResult& r) {
  std::map<std::string, int> by_quality;
  for (const int i : r.failed) {
    by_quality[i < static_cast<int>(r.matches.size()) ? ScanMatchQualityName(r.matches[i].quality)
                                                      : "malformed"]++;
  }
  std::string out = std::to_string(r.failed.size()) + " of " + std::to_string(r.size()) +
                    " scan matches failed (";
  std::string separator;
  for (const auto& [name, count] : by_quality) {
    out += separator + name + " " + std::to_string(count);
    separator = ", ";
  }
  return out + "): those scans are left out, as gaps";
}

// The same sample picked up again (a driver or logger that republishes the latest scan): the
// same beams and ranges, bit for bit (NaN included).
bool SameSample(const LaserScan& a, const LaserScan& b) {
  return a.angle_min_rad == b.angle_min_rad && a.angle_increment_rad == b.angle_increment_rad &&
         a.ranges_m.size() == b.ranges_m.size() &&
         std::memcmp(a.ranges_m.data(), b.ranges_m.data(), a.ranges_m.size() * sizeof(float)) == 0;
}

// The scans' indices without exact duplicates (a record written twice: the stamp and the ranges
// of the scan before); a stamp that repeats with other ranges, or goes back, is an error.
StatusOr<std::vector<size_t>> CheckInputs(const std::vector<LaserScan>& scans,
                                          const std::vector<EncoderSample>& encoders,
                                          const std::string& scans_name,
                                          const std::string& wheels_name, int* duplicates) {
  if (encoders.size() < 2) {
    return Status::InvalidInput(wheels_name + ": " + std::to_string(encoders.size()) +
                                " wheel-angle sample(s): at least two are needed");
  }
  std::vector<double> stamps;
  for (const EncoderSample& e : encoders) stamps.push_back(e.t_s);
  CALIB_RETURN_IF_ERROR(CheckStampUnit(stamps, wheels_name));
  stamps.clear();
  for (const LaserScan& scan : scans) stamps.push_back(scan.stamp_s);
  CALIB_RETURN_IF_ERROR(CheckStampUnit(stamps, scans_name));
  std::vector<size_t> rows;
  for (size_t i = 0; i < scans.size(); ++i) {
    if (i > 0 && scans[i].stamp_s == scans[i - 1].stamp_s && SameSample(scans[i], scans[i - 1])) {
      ++*duplicates;
      continue;
    }
    if (i > 0 && !(scans[i].stamp_s > scans[i - 1].stamp_s)) {
      const bool same = scans[i].stamp_s == scans[i - 1].stamp_s;
      return Status::InvalidInput(
          scans_name + ": record " + std::to_string(scans[i].record) + ": stamp " +
          Num(scans[i].stamp_s) + (same ? " repeats" : " does not follow") +
          " the previous scan's " + Num(scans[i - 1].stamp_s) +
          (same ? " with other ranges (a record written twice would repeat them)" : ""));
    }
    rows.push_back(i);
  }
  if (rows.size() < 3) {
    return Status::InvalidInput(scans_name + ": " + std::to_string(rows.size()) +
                                " scan(s): the calibration needs many scans of a moving robot");
  }
  return rows;
}

// The scans' period: the median step between their stamps (0 for fewer than two).
double ScanPeriod(const std::vector<const LaserScan*>& scans) {
  std::vector<double> steps;
  for (size_t i = 1; i < scans.size(); ++i) {
    steps.push_back(scans[i]->stamp_s - scans[i - 1]->stamp_s);
  }
  return UpperMedian(&steps);
}

// The longest sweep taken as one (max_sweep_periods of the scans' period), and a warning when
// some scans' sweeps are longer.
double MaxSweep(const std::vector<const LaserScan*>& scans, const ScanLogOptions& options,
                const std::string& scans_name, std::vector<std::string>* warnings) {
  if (scans.size() < 2) return 0.0;
  const double period_s = ScanPeriod(scans);
  const double max_sweep_s = options.max_sweep_periods * period_s;
  int longer = 0;
  const LaserScan* first = nullptr;
  for (const LaserScan* scan : scans) {
    if (std::abs(scan->SweepSeconds()) <= max_sweep_s) continue;
    ++longer;
    if (first == nullptr) first = scan;
  }
  if (longer > 0) {
    const auto seconds = [](double t) { return Num(std::round(t * 1e6) / 1e6) + " s"; };
    warnings->push_back(
        scans_name + ": " + std::to_string(longer) + " scan(s) (first: record " +
        std::to_string(first->record) + ") sweep for time_increment × (beams − 1) = " +
        seconds(first->SweepSeconds()) + ", longer than the scans' period " + seconds(period_s) +
        " (is time_increment in another unit?): those scans are taken as "
        "instantaneous, not de-skewed");
  }
  return max_sweep_s;
}

// The q-quantile of `values` (0 when empty).
double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  return KthSmallest(&values, std::min(values.size() - 1, static_cast<size_t>(q * values.size())));
}

// Below these motions per scan period (95th percentile) an unknown sweep smears a scan by less
// than the matcher's own noise.
constexpr double kUnskewedTurnRad = 0.5 * M_PI / 180.0;
constexpr double kUnskewedTravelM = 0.01;

// A warning when no scan says when its beams were measured (time_increment 0 in every one) and
// the robot moved enough between scans for a spinning lidar's sweep to matter: the scans are then
// matched as instantaneous, which biases the calibration on fast turns and runs.
void WarnInstantScans(const std::vector<const LaserScan*>& scans, const ScanOdometryResult& r,
                      const std::string& scans_name, std::vector<std::string>* warnings) {
  for (const LaserScan* scan : scans) {
    if (scan->time_increment_s != 0.0) return;
  }
  std::vector<double> turns, travels;
  for (int i = 0; i + 1 < r.size(); ++i) {
    if (r.chain[i] < 0 || r.chain[i] != r.chain[i + 1]) continue;
    const Pose2d step = Between(r.poses[i].world_T_sensor, r.poses[i + 1].world_T_sensor);
    turns.push_back(std::abs(WrapAngle(step(2))));
    travels.push_back(step.head<2>().norm());
  }
  const double turn = Quantile(turns, 0.95), travel = Quantile(travels, 0.95);
  if (turn < kUnskewedTurnRad && travel < kUnskewedTravelM) return;
  warnings->push_back(Format(
      "%s: every scan's time_increment is 0, so each scan is matched as if all its beams were "
      "measured at once; a spinning lidar sweeps over up to its period (%.0f ms here), in which "
      "this robot turned up to %.1f° and moved up to %.0f mm (95th percentiles per scan), enough "
      "to bias the calibration: if the lidar spins, give its rotation period with "
      "--lidar_rotation_period (s, e.g. 0.1 for 10 Hz) or record its driver's time_increment",
      scans_name.c_str(), 1e3 * ScanPeriod(scans), turn * 180.0 / M_PI, 1e3 * travel));
}

// Matches scans [begin, end), each seeded (and de-skewed) through the nominal wheels when known;
// start_s[i]: when scan i's sweep began on the wheels' clock.
StatusOr<ScanOdometryResult> MatchRun(const std::vector<const LaserScan*>& scans,
                                      const std::vector<double>& start_s, size_t begin, size_t end,
                                      const std::vector<EncoderSample>& encoders,
                                      const ScanLogOptions& options, double max_sweep_s) {
  const WheelsAndMounting robot = Nominal(options);
  const bool nominal = robot.known();
  ScanOdometry odometry(options.matching);
  for (size_t i = begin; i < end; ++i) {
    const LaserScan& scan = *scans[i];
    Pose2d guess = Pose2d::Zero();
    if (i > begin && nominal)
      guess = SensorMotionBetween(encoders, start_s[i - 1], start_s[i], robot);
    std::optional<SweepMotion> sweep;
    const double sweep_s = scan.SweepSeconds();
    if (options.deskew && nominal && sweep_s > 0.0 && sweep_s <= max_sweep_s) {
      sweep = SweepMotionOver(encoders, start_s[i], sweep_s, robot);
    }
    CALIB_RETURN_IF_ERROR(odometry.AddScan(scan, guess, sweep));
  }
  return odometry.result();
}

// `tail` after `head`: its scans' indices shift by head's size and its chains follow head's.
void Append(ScanOdometryResult tail, ScanOdometryResult* head) {
  const int offset = head->size();
  int chains = 0;
  for (const int c : head->chain) chains = std::max(chains, c + 1);
  for (int& k : tail.keyframe_of) k = k >= 0 ? k + offset : k;
  for (int& c : tail.chain) c = c >= 0 ? c + chains : c;
  for (int& f : tail.failed) f += offset;
  const auto append = [](auto& to, const auto& from) {
    to.insert(to.end(), from.begin(), from.end());
  };
  append(head->poses, tail.poses);
  append(head->matches, tail.matches);
  append(head->keyframe_of, tail.keyframe_of);
  append(head->covariances, tail.covariances);
  append(head->chain, tail.chain);
  append(head->failed, tail.failed);
}

// Long logs are matched in two halves on two threads: the halves are separate pose segments, so
// one interval (at the split) is lost.
constexpr size_t kScansPerThread = 1000;

// The runs matched apart: [begin, end) between the recording's restarts (each restart's first
// scan starts a run), a run of 2 × kScansPerThread scans or more in two halves.
std::vector<std::pair<size_t, size_t>> MatchRuns(const std::vector<const LaserScan*>& scans,
                                                 const std::vector<double>& restarts_s) {
  std::vector<size_t> cuts = {0};
  for (const double r : restarts_s) {
    const auto at = std::lower_bound(scans.begin(), scans.end(), r,
                                     [](const LaserScan* s, double t) { return s->stamp_s < t; });
    const size_t i = static_cast<size_t>(at - scans.begin());
    if (i > cuts.back() && i < scans.size()) cuts.push_back(i);
  }
  cuts.push_back(scans.size());
  std::vector<std::pair<size_t, size_t>> runs;
  for (size_t k = 0; k + 1 < cuts.size(); ++k) {
    const size_t begin = cuts[k], end = cuts[k + 1];
    if (end - begin < 2 * kScansPerThread) {
      runs.emplace_back(begin, end);
    } else {
      runs.emplace_back(begin, begin + (end - begin) / 2);
      runs.emplace_back(begin + (end - begin) / 2, end);
    }
  }
  return runs;
}

// Pose segments that start where no run does: the matching lost its track there (a run's own
// start, a thread's half or a restart of the recording, is no loss).
int LostTracks(const ScanOdometryResult& r, const std::vector<std::pair<size_t, size_t>>& runs) {
  std::set<size_t> planned;
  for (const auto& run : runs) planned.insert(run.first);
  std::set<int> seen;
  int lost = 0;
  for (size_t i = 0; i < r.chain.size(); ++i) {
    if (r.chain[i] >= 0 && seen.insert(r.chain[i]).second && !planned.count(i)) ++lost;
  }
  return lost;
}

StatusOr<ScanOdometryResult> MatchScans(const std::vector<const LaserScan*>& scans,
                                        const std::vector<double>& start_s,
                                        const std::vector<EncoderSample>& encoders,
                                        const ScanLogOptions& options, double max_sweep_s) {
  const std::vector<std::pair<size_t, size_t>> runs = MatchRuns(scans, options.restarts_s);
  const auto match = [&](size_t k) {
    return MatchRun(scans, start_s, runs[k].first, runs[k].second, encoders, options, max_sweep_s);
  };
  // Two at a time, on two threads.
  std::vector<StatusOr<ScanOdometryResult>> matched;
  for (size_t k = 0; k < runs.size(); k += 2) {
    std::future<StatusOr<ScanOdometryResult>> second;
    if (k + 1 < runs.size()) second = std::async(std::launch::async, match, k + 1);
    matched.push_back(match(k));
    if (second.valid()) matched.push_back(second.get());
  }
  for (const StatusOr<ScanOdometryResult>& m : matched) {
    if (!m.ok()) return m.status();
  }
  ScanOdometryResult out = std::move(matched.front()).value();
  for (size_t k = 1; k < matched.size(); ++k) Append(std::move(matched[k]).value(), &out);
  return out;
}

}  // namespace

StatusOr<ScanLog> LaserLogFromScans(const std::vector<LaserScan>& scans,
                                    const std::vector<EncoderSample>& encoders,
                                    const ScanLogNames& names, const ScanLogOptions& options) {
  const std::string& source = names.source;
  const std::string scans_name = names.scans.empty() ? source + " (scans)" : names.scans;
  const std::string wheels_name = names.wheels.empty() ? source + " (wheel angles)" : names.wheels;
  int duplicates = 0;
  CALIB_ASSIGN_OR_RETURN(const std::vector<size_t> rows,
                         CheckInputs(scans, encoders, scans_name, wheels_name, &duplicates));
  ScanLog out;
  if (duplicates > 0) {
    out.warnings.push_back(scans_name + ": " + std::to_string(duplicates) +
                           " exact duplicate scan(s) dropped (same stamp and ranges as the scan "
                           "before)");
  }
  // A repeated sample is not matched again: it gets its original's pose, which the streams then
  // count as a held repeat (its stamp is a pick-up time).
  std::vector<const LaserScan*> distinct;
  std::vector<int> distinct_of(scans.size(), -1);
  for (const size_t i : rows) {
    if (distinct.empty() || !SameSample(scans[i], *distinct.back())) {
      distinct.push_back(&scans[i]);
      out.distinct_scans.push_back(static_cast<int>(i));
    }
    distinct_of[i] = static_cast<int>(distinct.size()) - 1;
  }
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> start_s;
  for (size_t d = 0; d < distinct.size(); ++d) {
    start_s.push_back(options.sweep_starts(out.distinct_scans[d], distinct[d]->stamp_s));
  }
  const double max_sweep_s = MaxSweep(distinct, options, scans_name, &out.warnings);
  CALIB_ASSIGN_OR_RETURN(out.matching,
                         MatchScans(distinct, start_s, encoders, options, max_sweep_s));
  out.matching_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const ScanOdometryResult& r = out.matching;
  WarnInstantScans(distinct, r, scans_name, &out.warnings);
  out.failed_matches = static_cast<int>(r.failed.size());
  std::set<int> segments, keyframes;
  std::vector<StampedPose> poses;
  for (const size_t i : rows) {
    const int d = distinct_of[i];
    if (r.chain[d] < 0) continue;
    StampedPose p = r.poses[d];
    p.t_s = scans[i].stamp_s;
    p.line = static_cast<int>(scans[i].record) + 1;  // 1-based, as a line.
    p.segment = r.chain[d];
    segments.insert(p.segment);
    if (r.keyframe_of[d] >= 0) keyframes.insert(r.keyframe_of[d]);
    poses.push_back(p);
  }
  const auto unmatched = [&](const Status& why) -> StatusOr<ScanLog> {
    if (!options.keep_unmatched) return why;
    out.log.source = source;
    out.log.streams.odometry = encoders;
    out.unmatched = why.message();
    return out;
  };
  if (keyframes.empty()) {  // No scan was matched against another.
    int degenerate = 0;
    for (const int i : r.failed) {
      degenerate += i < static_cast<int>(r.matches.size()) &&
                    r.matches[i].quality == ScanMatchQuality::kDegenerate;
    }
    const std::string hint =
        2 * degenerate > static_cast<int>(r.failed.size())
            ? "the walls leave a direction of motion unconstrained (a featureless corridor, an "
              "open space)"
            : "are the ranges valid (within range_min and range_max)?";
    return unmatched(Status::InvalidInput(
        scans_name + ": no two scans could be matched: " + FailureSummary(r) + "; " + hint));
  }
  out.segments = static_cast<int>(segments.size());
  out.keyframes = static_cast<int>(keyframes.size());
  if (out.failed_matches > 0) out.warnings.push_back(FailureSummary(r));
  const int lost = LostTracks(r, MatchRuns(distinct, options.restarts_s));
  if (lost > 0) {
    out.warnings.push_back("the scan matching lost its track " + std::to_string(lost) +
                           " time(s) and restarted: no interval spans a restart");
  }
  StatusOr<LaserLog> log = LaserLogFromStreams(encoders, poses, source, wheels_name,
                                               scans_name + " (scan-matched poses)");
  if (!log.ok()) return unmatched(log.status());
  out.log = std::move(log).value();
  return out;
}

}  // namespace calib
