#include <calib/tools/report/laser_report.h>
#include <calib/tools/report/latent_timing_report.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace calib {
namespace {

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

// The largest |stamp-as-truth − timing-aware| in units of the timing-aware σ.
double LargestShift(const LaserTimingResult& r, int* which) {
  const LaserParamVector shift =
      (r.stamps_as_truth.estimate.ToVector() - r.calibration.estimate.ToVector())
          .cwiseQuotient(r.calibration.stddev.cwiseMax(1e-300));
  return shift.cwiseAbs().maxCoeff(which);
}

}  // namespace

nlohmann::ordered_json LatentTimingJson(const LaserTimingResult& r) {
  nlohmann::ordered_json out;
  out["sensor_clock"] = r.sensor_clock;
  out["time_offset_s"] = r.time_offset_s;
  out["time_offset_stddev_s"] = r.time_offset_stddev_s;
  out["sensor_jitter_s"] = r.sensor_jitter_s;
  out["encoder_jitter_s"] = r.encoder_jitter_s;
  out["sensor_period_s"] = r.sensor_period_s;
  out["sensor_period_stddev_s"] = r.sensor_period_stddev_s;
  out["clock_drift_s"] = r.clock_drift_s;
  out["scores"] = nlohmann::ordered_json::object();
  if (r.stamps_score) out["scores"]["stamps"] = *r.stamps_score;
  if (r.free_running_score) out["scores"]["free_running"] = *r.free_running_score;
  out["intervals"] = r.intervals;
  out["held_repeats_dropped"] = r.held_repeats_dropped;
  out["samples_outside_encoder_span"] = r.outside_encoder_span;
  out["neighbour_error_correlation"] = {r.neighbour_correlation(0), r.neighbour_correlation(1),
                                        r.neighbour_correlation(2)};
  out["pose_errors"] = r.pose_errors;
  out["rounds"] = r.rounds;
  out["seconds"] = r.seconds;
  out["sample_time_stddev_s"] = {
      {"median", Median(r.sample_time_stddev_s)},
      {"max", r.sample_time_stddev_s.empty() ? 0.0
                                             : *std::max_element(r.sample_time_stddev_s.begin(),
                                                                 r.sample_time_stddev_s.end())}};
  out["samples"] = {
      {"line", r.sample_line}, {"time_s", r.sample_time_s}, {"stddev_s", r.sample_time_stddev_s}};
  out["stamps_as_truth"] = {{"estimate", LaserParamJson(r.stamps_as_truth.estimate.ToVector())},
                            {"stddev", LaserParamJson(r.stamps_as_truth.stddev)}};
  out["warnings"] = r.warnings;
  return out;
}

nlohmann::ordered_json LatentTimingFinding(const LaserTimingResult& r) {
  int which = 0;
  const double shift = LargestShift(r, &which);
  const bool significant = shift > 3.0;
  char text[400];
  if (significant) {
    std::snprintf(text, sizeof(text),
                  "Timing modelled: the sample times are not the stamps (%s, mean offset %.1f ± "
                  "%.1f ms); taking the stamps as sample times would move %s by %.1f σ.",
                  r.sensor_clock == "free_running" ? "a free-running sensor clock picked up late"
                                                   : "stamp jitter about a common offset",
                  1e3 * r.time_offset_s, 1e3 * r.time_offset_stddev_s,
                  kLaserParamNames[which].c_str(), shift);
  } else {
    std::snprintf(text, sizeof(text),
                  "No timing effect: with the sample times estimated, no parameter moves by more "
                  "than %.1f σ from the calibration that takes the stamps as sample times.",
                  shift);
  }
  nlohmann::ordered_json f;
  f["effect"] = "sample_times";
  f["significant"] = significant;
  f["value"] = r.time_offset_s;
  f["stddev"] = r.time_offset_stddev_s;
  f["unit"] = "s";
  f["statement"] = text;
  f["sensor_clock"] = r.sensor_clock;
  f["stamps_as_truth_shift_sigma"] = shift;
  return f;
}

std::string LatentTimingSummary(const LaserTimingResult& r) {
  char line[400];
  std::string text;
  if (r.sensor_clock == "free_running") {
    std::snprintf(line, sizeof(line),
                  "  timing: latent sample times, free-running sensor clock: period %.4f ± "
                  "%.4f ms, drift %.1f ms, mean pick-up lag %.1f ± %.1f ms; encoder jitter "
                  "%.1f ms\n",
                  1e3 * r.sensor_period_s, 1e3 * r.sensor_period_stddev_s, 1e3 * r.clock_drift_s,
                  -1e3 * r.time_offset_s, 1e3 * r.time_offset_stddev_s, 1e3 * r.encoder_jitter_s);
  } else {
    std::snprintf(line, sizeof(line),
                  "  timing: latent sample times, stamps + offset %.1f ± %.1f ms + jitter "
                  "(sensor %.1f ms, encoder %.1f ms)\n",
                  1e3 * r.time_offset_s, 1e3 * r.time_offset_stddev_s, 1e3 * r.sensor_jitter_s,
                  1e3 * r.encoder_jitter_s);
  }
  text += line;
  if (r.pose_errors) {
    std::snprintf(line, sizeof(line),
                  "  timing: neighbouring intervals' errors correlate (%.2f, %.2f, %.2f; x, y, θ): "
                  "the scan poses err independently of one another, and the σ's count it\n",
                  r.neighbour_correlation(0), r.neighbour_correlation(1),
                  r.neighbour_correlation(2));
    text += line;
  }
  int which = 0;
  const double shift = LargestShift(r, &which);
  std::snprintf(line, sizeof(line),
                "  timing: taking the stamps as sample times would move %s by %.1f σ\n",
                kLaserParamNames[which].c_str(), shift);
  text += line;
  return text;
}

void AddLatentTimingToDiagnosis(const LaserTimingResult& result, nlohmann::ordered_json* json) {
  const nlohmann::ordered_json finding = LatentTimingFinding(result);
  (*json)["findings"].insert((*json)["findings"].begin(), finding);
  if (finding["significant"].get<bool>()) {
    (*json)["final"]["effects"].insert((*json)["final"]["effects"].begin(), "sample_times");
    (*json)["adopted"].insert((*json)["adopted"].begin(), "sample_times");
  }
  (*json)["timing"]["treatment"] = "latent_times";
  (*json)["timing"]["latent_times"] = LatentTimingJson(result);
}

}  // namespace calib
