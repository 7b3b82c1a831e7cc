#include <calib/tools/report/consistency_report.h>
#include <calib/tools/report/json_output.h>
#include <calib/tools/report/laser_report.h>

#include <cmath>
#include <cstdio>

namespace calib {

nlohmann::ordered_json LaserParamJson(const LaserParamVector& v) {
  nlohmann::ordered_json object;
  for (int i = 0; i < kNumLaserParams; ++i) object[kLaserParamNames[i]] = v(i);
  return object;
}

namespace {

const auto& ParamObject = LaserParamJson;  // The local name this file has always used.

// Display units: mm for lengths, degrees for the angle.

// timing.interval_jitter: the boundary-stamp jitter of each log (tuple/CSV logs).
nlohmann::ordered_json IntervalJitterJson(const LaserCalibrationResult& result) {
  nlohmann::ordered_json logs = nlohmann::ordered_json::array();
  std::vector<std::string> statements;
  for (const IntervalJitterEstimate& jitter : result.interval_jitter) {
    logs.push_back({{"jitter_s", jitter.jitter_s},
                    {"jitter_stddev_s", jitter.jitter_stddev_s},
                    {"lr_statistic", jitter.lr_statistic},
                    {"p_value", jitter.p_value},
                    {"significant", jitter.significant},
                    {"scan_noise_sigma",
                     {{"x", jitter.noise_sigma(0)},
                      {"y", jitter.noise_sigma(1)},
                      {"theta", jitter.noise_sigma(2)}}},
                    {"intervals", jitter.intervals_used}});
    if (jitter.significant) statements.push_back(IntervalJitterStatement(jitter));
  }
  return {{"refit", result.jitter_refit}, {"logs", logs}, {"statements", statements}};
}

}  // namespace

nlohmann::ordered_json LaserResultJson(const LaserCalibrationResult& result,
                                       const std::string& input, const std::string& loss,
                                       const std::vector<StreamTiming>& stream_timing) {
  nlohmann::ordered_json out = ReportHeader("laser", input, "m, rad");
  out["estimate"] = ParamObject(result.estimate.ToVector());
  out["stddev"] = ParamObject(result.stddev);
  out["closed_form"] = ParamObject(result.closed_form.calibration.ToVector());
  out["closed_form_trimmed"] = ParamObject(result.closed_form_trimmed.calibration.ToVector());
  out["samples"] = result.samples;
  out["inliers"] = result.inliers;
  out["gross_outlier_share"] = result.outlier_share;
  out["loss"] = loss;
  out["loss_stages"] = result.loss.empty() ? loss : result.loss;
  out["covariance"] = {{"order", kLaserParamNames}, {"matrix", MatrixJson(result.covariance)}};
  nlohmann::ordered_json noise = nlohmann::ordered_json::array();
  for (const Eigen::Vector3d& sigma : result.noise_sigma) {
    noise.push_back({{"x", sigma(0)}, {"y", sigma(1)}, {"theta", sigma(2)}});
  }
  out["scan_noise_sigma"] = noise;
  out["covariance_scale"] = result.covariance_scale;
  out["motion"] = {{"still", result.census.still},
                   {"pure_rotation", result.census.pure_rotation},
                   {"straight", result.census.straight},
                   {"arc", result.census.arc}};
  nlohmann::ordered_json direction;
  for (int i = 0; i < kNumLaserParams; ++i) {
    direction[kLaserParamNames[i]] = result.observability.weakest_direction(i);
  }
  out["observability"] = {{"relative_stddev", ParamObject(result.observability.relative_sigma)},
                          {"weakest_direction", direction},
                          {"weakest_relative_stddev", result.observability.weakest_relative_sigma},
                          {"condition_number", result.observability.condition_number},
                          {"summary", result.observability.weakest_description},
                          {"warnings", result.observability.warnings}};
  out["closed_form_detail"] = {{"J21", result.closed_form.j21},
                               {"J22", result.closed_form.j22},
                               {"J_condition_number", result.closed_form.j_condition_number},
                               {"gross_intervals_left_out", result.gross_intervals}};
  if (!result.interval_jitter.empty()) {
    out["timing"]["treatment"] = "interval_jitter";
    out["timing"]["interval_jitter"] = IntervalJitterJson(result);
  }
  out["consistency"] = LaserConsistencyJson(result.consistency);
  out["iterations"] = result.iterations;
  out["converged"] = result.converged;
  out["seconds"] = {{"closed_form", result.closed_form_seconds},
                    {"refinement", result.refinement_seconds},
                    {"covariance", result.covariance_seconds}};
  if (!stream_timing.empty()) out["timing"]["streams"] = StreamTimingJson(stream_timing);
  return out;
}

nlohmann::ordered_json LaserSimTruthJson(const LaserSimTruth& truth) {
  nlohmann::ordered_json json;
  json["problem"] = "laser";
  json["estimate"] = ParamObject(LaserCalibration{truth.odometry, truth.base_T_sensor}.ToVector());
  json["effects"] = {{"time_offset", truth.effects.time_offset_s},
                     {"lateral_slip", truth.effects.lateral_slip_s},
                     {"longitudinal_slip", truth.effects.longitudinal_slip_s},
                     {"wheel_radius_change", truth.effects.radius_change_time_s},
                     {"r_l_after", truth.effects.left_radius_after_m},
                     {"r_r_after", truth.effects.right_radius_after_m}};
  return json;
}

std::string LaserResultSummary(const LaserCalibrationResult& result, const std::string& input,
                               const std::string& loss,
                               const std::vector<StreamTiming>& stream_timing) {
  std::string text;
  char line[256];
  std::snprintf(line, sizeof(line), "%s: laser–odometry calibration, %d intervals, loss %s\n",
                input.c_str(), result.samples,
                result.loss.empty() ? loss.c_str() : result.loss.c_str());
  text += line;
  std::snprintf(line, sizeof(line), "  %-18s %12s   %-10s %12s\n", "parameter", "estimate", "± σ",
                "closed form");
  text += line;
  const LaserParamVector estimate = result.estimate.ToVector();
  const LaserParamVector closed = result.closed_form.calibration.ToVector();
  for (int i = 0; i < kNumLaserParams; ++i) {
    const double k = kLaserParams[i].display_scale;
    const std::string name =
        kLaserParams[i].name + std::string(" [") + kLaserParams[i].display_unit + "]";
    std::snprintf(line, sizeof(line), "  %-18s %12.4f ± %-10.4f %12.4f\n", name.c_str(),
                  estimate(i) * k, result.stddev(i) * k, closed(i) * k);
    text += line;
  }
  if (!result.gross_note.empty()) text += "  " + result.gross_note + "\n";
  if (loss == "none") {
    // Without a robust loss every interval weighs fully: the cut only names the large ones.
    std::snprintf(line, sizeof(line),
                  "  all %d intervals weigh fully (no robust loss); %d lie beyond the inlier cut\n",
                  result.samples, result.samples - result.inliers);
  } else {
    std::snprintf(line, sizeof(line), "  inliers %d of %d\n", result.inliers, result.samples);
  }
  text += line;
  for (const Eigen::Vector3d& sigma : result.noise_sigma) {
    std::snprintf(line, sizeof(line),
                  "  scan noise of the inliers: σx %.3f mm, σy %.3f mm, σθ %.4f deg\n",
                  sigma(0) * 1e3, sigma(1) * 1e3, sigma(2) * 180.0 / M_PI);
    text += line;
  }
  for (const IntervalJitterEstimate& jitter : result.interval_jitter) {
    std::snprintf(line, sizeof(line),
                  "  timing: boundary-stamp jitter σ = %.1f ± %.1f ms (p = %.2g): %s\n",
                  jitter.jitter_s * 1e3, jitter.jitter_stddev_s * 1e3, jitter.p_value,
                  jitter.significant ? "modelled in each interval's covariance"
                                     : "not significant, not modelled");
    text += line;
  }
  text += "  observability: " + result.observability.weakest_description + "\n";
  text += LaserConsistencySummary(result.consistency);
  for (const std::string& warning : result.observability.warnings) {
    text += "  warning: " + warning + "\n";
  }
  text += StreamTimingSummary(stream_timing);
  return text;
}

}  // namespace calib
