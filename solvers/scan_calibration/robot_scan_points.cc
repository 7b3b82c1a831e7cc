#include <calib/core/text_number.h>
#include <calib/solvers/scan_calibration/robot_scan_points.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

namespace calib {

StatusOr<ScanPointCalibration> RefineRobotOnScanPoints(const RobotMessages& bag,
                                                       const RobotBagCalibration& two_stage,
                                                       const ScanPointOptions& options) {
  const RobotBagLog& log = two_stage.log;
  const LaserTimingResult& timing = two_stage.result;
  const std::vector<LaserScan>& scans = bag.scans.at(log.topics.scan_topic);
  // The timing's samples are named by their line, the scan's record + 1. A timing whose offset
  // the intervals hardly determine (σ over a quarter of the scan period: few intervals, e.g. a
  // corridor's degenerate matches) would place the beams anywhere; then the stamps are the start
  // and the refinement's own offset δ takes the timing up.
  std::unordered_map<int64_t, double> time_of_line;
  const bool timed = !(timing.time_offset_stddev_s > 0.25 * timing.sensor_period_s);
  for (size_t k = 0; timed && k < timing.sample_line.size() && k < timing.sample_time_s.size();
       ++k) {
    time_of_line[timing.sample_line[k]] = timing.sample_time_s[k];
  }
  std::vector<double> corrections;
  for (const int i : log.scans.distinct_scans) {
    const auto it = time_of_line.find(scans[i].record + 1);
    if (it != time_of_line.end()) corrections.push_back(it->second - scans[i].stamp_s);
  }
  double median_correction_s = 0.0;
  if (!corrections.empty()) {
    auto middle = corrections.begin() + corrections.size() / 2;
    std::nth_element(corrections.begin(), middle, corrections.end());
    median_correction_s = *middle;
  }
  std::vector<LaserScan> mirrored;
  if (log.mirrored) mirrored.reserve(log.scans.distinct_scans.size());
  ScanPointInput input;
  input.encoders = &log.scans.log.streams.odometry;
  input.source = bag.source + " " + log.topics.scan_topic;
  for (const int i : log.scans.distinct_scans) {
    const auto it = time_of_line.find(scans[i].record + 1);
    const double t = it != time_of_line.end() ? it->second : scans[i].stamp_s + median_correction_s;
    // A scan the timing did not place may fall out of order with its timed neighbours.
    if (!input.first_beam_time_s.empty() && !(t > input.first_beam_time_s.back())) continue;
    if (log.mirrored) mirrored.push_back(MirroredScan(scans[i]));
    input.scans.push_back(log.mirrored ? &mirrored.back() : &scans[i]);
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
  if (out.ok() && !timed) {
    out->warnings.push_back("the scan timing of the two-stage route is undetermined (offset σ " +
                            Num(std::round(1e3 * timing.time_offset_stddev_s)) +
                            " ms): the scan points started from the stamps");
  }
  return out;
}

}  // namespace calib
