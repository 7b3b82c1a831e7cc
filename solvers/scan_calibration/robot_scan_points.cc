#include <calib/core/text_number.h>
#include <calib/solvers/scan_calibration/robot_scan_points.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace calib {

StatusOr<ScanPointCalibration> RefineRobotOnScanPoints(const RobotMessages& bag,
                                                       const RobotBagCalibration& two_stage,
                                                       const ScanPointOptions& options) {
  const RobotBagLog& log = two_stage.log;
  const LaserTimingResult& timing = two_stage.result;
  const std::vector<LaserScan>& scans = bag.scans.at(log.topics.scan_topic);
  // A timing whose offset the intervals hardly determine would place the beams anywhere; then
  // the stamps are the start and the refinement's own offset δ takes the timing up.
  const SweepStarts placed = ScanSweepStarts(scans, timing);
  const bool timed = !placed.start_s.empty();
  const auto placed_at = [&](int i) {
    return timed ? placed.start_s[i] : std::numeric_limits<double>::quiet_NaN();
  };
  std::vector<double> corrections;
  for (const int i : log.scans.distinct_scans) {
    if (std::isfinite(placed_at(i))) corrections.push_back(placed_at(i) - scans[i].stamp_s);
  }
  double median_correction_s = 0.0;
  if (!corrections.empty()) {
    auto middle = corrections.begin() + corrections.size() / 2;
    std::nth_element(corrections.begin(), middle, corrections.end());
    median_correction_s = *middle;
  }
  // The scans as the matching saw them: mirrored (an upside-down sensor), their beams in the order
  // measured when the check of their timing changed it.
  const bool changed = log.beam_timing && log.beam_timing->changed;
  const bool prepare = log.mirrored || changed;
  std::vector<LaserScan> prepared;
  if (prepare) prepared.reserve(log.scans.distinct_scans.size());
  ScanPointInput input;
  input.encoders = &log.scans.log.streams.odometry;
  input.source = bag.source + " " + log.topics.scan_topic;
  for (const int i : log.scans.distinct_scans) {
    const double t =
        std::isfinite(placed_at(i)) ? placed_at(i) : scans[i].stamp_s + median_correction_s;
    // A scan the timing did not place may fall out of order with its timed neighbours.
    if (!input.first_beam_time_s.empty() && !(t > input.first_beam_time_s.back())) continue;
    if (prepare) {
      const LaserScan scan = log.mirrored ? MirroredScan(scans[i]) : scans[i];
      prepared.push_back(changed ? WithBeamTiming(scan, log.beam_timing->chosen) : scan);
    }
    input.scans.push_back(prepare ? &prepared.back() : &scans[i]);
    input.first_beam_time_s.push_back(t);
  }
  StatusOr<ScanPointCalibration> out =
      CalibrateOnScanPoints(input, timing.calibration.estimate, options);
  if (out.ok() && !out->converged) {
    // Still moving and far from the walls (σ̂ well above the matcher's): not an estimate.
    std::vector<double> sigmas;
    for (const ScanMatch& m : log.scans.matching.matches) {
      if (m.ok()) sigmas.push_back(m.range_sigma_m);
    }
    if (!sigmas.empty()) {
      std::nth_element(sigmas.begin(), sigmas.begin() + sigmas.size() / 2, sigmas.end());
      const double matcher_sigma_m = sigmas[sigmas.size() / 2];
      if (out->range_sigma_m > 3.0 * matcher_sigma_m) {
        return Status::NotConverged("it did not settle: its points lie " +
                                    Num(std::round(1e4 * out->range_sigma_m) / 10) +
                                    " mm (robust σ) from their lines, the scan matcher's " +
                                    Num(std::round(1e4 * matcher_sigma_m) / 10) + " mm");
      }
    }
  }
  if (out.ok() && !timed && two_stage.two_stage_failed.empty()) {
    out->warnings.push_back("the scan timing of the two-stage route is undetermined (offset σ " +
                            Num(std::round(1e3 * timing.time_offset_stddev_s)) +
                            " ms): the scan points started from the stamps");
  }
  return out;
}

namespace {

// The scan points' result in the two-stage result's place, so that reports and deployment read
// it as they read a refinement: the same estimate, the start as its "closed form", the stamps as
// the sample times (the refinement's offset δ is the timing).
LaserTimingResult ScanPointsInTwoStagePlace(const ScanPointCalibration& refined,
                                            const LaserCalibration& start,
                                            const std::string& warning) {
  LaserTimingResult out;
  LaserCalibrationResult& c = out.calibration;
  c.estimate = refined.estimate;
  c.covariance = refined.covariance;
  c.stddev = refined.stddev;
  c.closed_form.calibration = start;
  c.closed_form_trimmed.calibration = start;
  c.samples = refined.pairs;
  c.inliers = static_cast<int>(std::lround(refined.inlier_fraction * refined.pairs));
  c.converged = refined.converged;
  c.loss = "scan points";
  c.warnings.push_back(warning);
  c.observability.weakest_description =
      "not analysed (the intervals of the two-stage route are too few)";
  c.consistency.note = "not checked (it reads the two-stage route's intervals, too few here)";
  out.stamps_as_truth = c;
  out.sensor_clock = "stamps";
  out.warnings.push_back(warning);
  return out;
}

}  // namespace

StatusOr<RobotBagCalibration> CalibrateOnScanPointsAlone(const RobotMessages& bag,
                                                         const RobotBagOptions& options,
                                                         RobotBagLog log, const Status& why) {
  if (!options.scan_points) return why;
  if (!(options.nominal_wheel_radius_m > 0.0 && options.nominal_wheelbase_m > 0.0)) {
    return Status(why.code(), why.message() +
                                  "; the refinement on the scan points could start without the "
                                  "two-stage route from the nominal wheels (give "
                                  "--nominal_wheel_radius and --nominal_wheelbase)");
  }
  LaserCalibration start;
  start.odometry = {options.nominal_wheel_radius_m, options.nominal_wheel_radius_m,
                    options.nominal_wheelbase_m};
  start.base_T_sensor =
      log.nominal_mounting ? log.nominal_mounting->base_T_sensor : Pose2d(Pose2d::Zero());
  RobotBagCalibration out;
  out.log = std::move(log);
  out.two_stage_failed = why.message();
  out.result.calibration.estimate = start;
  // An undetermined two-stage timing: the refinement starts from the stamps.
  out.result.time_offset_stddev_s = std::numeric_limits<double>::infinity();
  StatusOr<ScanPointCalibration> refined = RefineRobotOnScanPoints(bag, out, *options.scan_points);
  if (!refined.ok()) {
    return Status(why.code(), why.message() +
                                  "; the refinement on the scan points from the "
                                  "nominal wheels failed too (" +
                                  refined.message() + ")");
  }
  const std::string warning =
      "the two-stage route could not calibrate this recording (" + why.message() +
      "): the result is the refinement on the scan points alone, started from the nominal wheels" +
      (out.log.nominal_mounting ? " and tf's mounting" : " and a zero mounting") +
      " (shown as its closed form)";
  out.result = ScanPointsInTwoStagePlace(*refined, start, warning);
  refined->warnings.insert(refined->warnings.begin(), warning);
  out.scan_points = std::move(refined).value();
  return out;
}

}  // namespace calib
