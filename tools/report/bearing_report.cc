#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/json_output.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace calib {
namespace {

// "phi [deg]", "delta" (no unit): a parameter's row label in the summary.
std::string Label(const ParamInfo& param) {
  const std::string unit = param.display_unit;
  return unit.empty() ? std::string(param.name) : param.name + (" [" + unit + "]");
}

// The calibration's timing model (keys as the laser's "timing" object): what was modelled, τ ± σ
// and the stamp jitter. Set key by key so that other entries of "timing" stay.
void AddTimingJson(const BearingTiming& timing, nlohmann::ordered_json* out) {
  nlohmann::ordered_json& t = (*out)["timing"];
  t["treatment"] = timing.treatment;
  t["time_offset_s"] = timing.time_offset_s;
  t["time_offset_stddev_s"] = timing.time_offset_stddev_s;
  t["time_offset_modelled"] = timing.time_offset_modelled;
  t["time_offset_test"] = {{"tested", timing.time_offset_tested},
                           {"free_estimate_s", timing.time_offset_free_s},
                           {"lr_statistic", timing.time_offset_lr},
                           {"p_value", timing.time_offset_p_value}};
  const BearingJitterEstimate& j = timing.jitter;
  t["jitter_s"] = timing.jitter_modelled ? j.jitter_s : 0.0;
  t["jitter_stddev_s"] = j.jitter_stddev_s;
  t["jitter_modelled"] = timing.jitter_modelled;
  t["jitter_test"] = {{"tested", timing.jitter_tested},
                      {"estimate_s", j.jitter_s},
                      {"lr_statistic", j.lr_statistic},
                      {"p_value", j.p_value},
                      {"bearings_used", j.bearings_used},
                      {"bearing_sigma_without_jitter_rad", j.bearing_sigma_without_jitter_rad}};
  t["jitter_model"] =
      "bearing variance sigma_beta^2 + jitter^2 * (d beta/dt)^2; the jitter is the scatter of the "
      "bearing times against the encoder clock (bearing or encoder stamps)";
  const BearingClockEstimate& c = timing.clock;
  t["sensor_clock_modelled"] = timing.clock_modelled;
  t["sensor_clock"] = {{"free_running", c.free_running},
                       {"period_determined", c.period_determined},
                       {"period_s", c.period_s},
                       {"period_stddev_s", c.period_stddev_s},
                       {"stamp_step_s", c.stamp_step_s},
                       {"held_samples", c.held_samples},
                       {"skipped_samples", c.skipped_samples},
                       {"counted_steps", c.counted_steps},
                       {"held_bearings_dropped", timing.held_bearings_dropped},
                       {"bearings_before_encoders", timing.bearings_before_encoders},
                       {"refit_lr_statistic", timing.clock_confirm_lr},
                       {"refit_p_value", timing.clock_confirm_p_value}};
  t["statement"] = timing.statement;
}

}  // namespace

nlohmann::ordered_json BearingParamObject(const BearingParamVector& v,
                                          const BearingMetricVector* metric) {
  nlohmann::ordered_json object;
  for (int i = 0; i < kNumBearingParams; ++i) object[kBearingParamNames[i]] = v(i);
  if (metric != nullptr) {
    for (int i = kBearingMetricRho; i < kNumBearingMetricParams; ++i)
      object[kBearingMetricNames[i]] = (*metric)(i);
  }
  return object;
}

bool IsBearingLogDirectory(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return false;
  return fs::exists(fs::path(path) / "bearings.csv", ec) ||
         fs::exists(fs::path(path) / "meta.json", ec);
}

nlohmann::ordered_json BearingResultJson(const BearingCalibrationResult& result,
                                         const std::string& input, const std::string& loss,
                                         const std::vector<StreamTiming>& stream_timing) {
  nlohmann::ordered_json out = ReportHeader("bearing", input, "m, rad; eta and xi in 1/m");
  const BearingMetricVector metric = ToVector(result.metric);
  const BearingMetricVector seed_metric = ToVector(result.seed_metric);
  out["estimate"] =
      BearingParamObject(ToVector(result.estimate), result.has_metric ? &metric : nullptr);
  out["stddev"] =
      BearingParamObject(result.stddev, result.has_metric ? &result.metric_stddev : nullptr);
  out["closed_form"] =
      BearingParamObject(ToVector(result.seed), result.has_seed_metric ? &seed_metric : nullptr);
  out["closed_form_method"] =
      result.seed_method == BearingSeedMethod::kClosedForm
          ? "Martinelli's closed form on the circular runs"
          : "coarse search (the closed form does not apply: " + result.closed_form_message + ")";
  out["samples"] = result.samples;
  out["inliers"] = result.inliers;
  out["gross_outlier_share"] = result.outlier_share;
  out["converged"] = result.converged;
  out["warnings"] = result.warnings;
  out["loss"] = loss;
  out["loss_stages"] = result.loss.empty() ? loss : result.loss;
  out["gauge"] =
      result.has_metric
          ? "metric: the initial distance fixes the scale; eta, delta, xi are the observable set"
          : "scale-free: delta_r = 1 (lengths in units of delta_r metres); only phi, psi, eta, "
            "delta, xi are observable without an initial distance";
  nlohmann::ordered_json order = nlohmann::ordered_json::array();
  for (const char* name : kBearingParamNames) order.push_back(name);
  out["covariance"] = {{"order", order}, {"matrix", MatrixJson(result.covariance)}};
  if (result.has_metric) {
    nlohmann::ordered_json metric_order = nlohmann::ordered_json::array();
    for (const char* name : kBearingMetricNames) metric_order.push_back(name);
    out["metric_covariance"] = {{"order", metric_order},
                                {"matrix", MatrixJson(result.metric_covariance)}};
  }
  out["noise"] = {{"bearing_sigma_rad", result.noise.bearing_sigma_rad},
                  {"bearing_sigma_estimated", result.bearing_sigma_estimated},
                  {"encoder_k", result.noise.encoder_k},
                  {"encoder_k_estimated", result.encoder_k_estimated},
                  {"encoder_k_data_estimate", result.encoder_k_estimate},
                  {"encoder_k_for_covariance", result.covariance_encoder_k},
                  {"bearing_redundancy", result.bearing_redundancy},
                  {"odometry_redundancy", result.odometry_redundancy}};
  out["covariance_scale"] = result.covariance_scale;
  nlohmann::ordered_json runs = nlohmann::ordered_json::array();
  for (const BearingRunSummary& run : result.runs) {
    nlohmann::ordered_json r = {{"run", run.run},
                                {"bearings", run.bearings},
                                {"inliers", run.inliers},
                                {"circular", run.circular}};
    if (run.circular) r["q"] = run.q;
    r["start_distance"] = run.start_distance;
    if (result.has_metric) r["start_distance_m"] = run.start_distance * result.metric.delta_r;
    r["rms_residual_rad"] = run.rms_residual_rad;
    runs.push_back(r);
  }
  out["runs"] = runs;
  if (result.has_closed_form) {
    nlohmann::ordered_json cf = nlohmann::ordered_json::array();
    for (const MartinelliRunEstimate& run : result.closed_form.runs) {
      cf.push_back({{"run", run.run},
                    {"q", run.q},
                    {"xi_q", run.xi_q_per_m},
                    {"L", run.l_rad},
                    {"k", run.k_per_m},
                    {"c", run.c_rad},
                    {"periods_covered", run.periods_covered},
                    {"rms_residual_rad", run.rms_residual_rad}});
    }
    out["closed_form_runs"] = cf;
  }
  out["iterations"] = result.iterations;
  out["noise_rounds"] = result.noise_rounds;
  out["seconds"] = {{"seed", result.seed_seconds},
                    {"adjustment", result.adjustment_seconds},
                    {"covariance", result.covariance_seconds}};
  if (!stream_timing.empty()) out["timing"] = {{"streams", StreamTimingJson(stream_timing)}};
  // After the streams' hook: adds keys beside "streams" (none when the timing was not tested).
  if (result.timing.time_offset_tested || result.timing.jitter_tested) {
    AddTimingJson(result.timing, &out);
  }
  return out;
}

std::string BearingResultSummary(const BearingCalibrationResult& result, const std::string& input,
                                 const std::string& loss,
                                 const std::vector<StreamTiming>& stream_timing) {
  std::string text;
  char line[256];
  std::snprintf(line, sizeof(line),
                "%s: bearing-only calibration, %zu runs, %d bearings (%d inliers), loss %s\n",
                input.c_str(), result.runs.size(), result.samples, result.inliers,
                result.loss.empty() ? loss.c_str() : result.loss.c_str());
  text += line;
  std::snprintf(
      line, sizeof(line), "  %-14s %14s   %-12s %14s\n", "parameter", "estimate", "± σ",
      result.seed_method == BearingSeedMethod::kClosedForm ? "closed form" : "search seed");
  text += line;
  const auto row = [&](const std::string& name, double value, double sigma, double seed,
                       double scale) {
    std::snprintf(line, sizeof(line), "  %-14s %14.6f ± %-12.6f %14.6f\n", name.c_str(),
                  value * scale, sigma * scale, seed * scale);
    text += line;
  };
  const BearingParamVector e = ToVector(result.estimate), s = ToVector(result.seed);
  for (int i = 0; i < kNumBearingParams; ++i) {
    row(Label(kBearingParams[i]), e(i), result.stddev(i), s(i), kBearingParams[i].display_scale);
  }
  if (result.has_metric) {
    const BearingMetricVector m = ToVector(result.metric), sm = ToVector(result.seed_metric);
    for (int i = kBearingMetricRho; i < kNumBearingMetricParams; ++i) {
      row(Label(kBearingMetricParams[i]), m(i), result.metric_stddev(i), sm(i),
          kBearingMetricParams[i].display_scale);
    }
  } else {
    text +=
        "  no initial distance in meta.json: the metric scale (rho, delta_r, delta_l, "
        "delta_b) is not observable\n";
  }
  const double deg = 180.0 / M_PI;  // σβ in degrees.
  std::snprintf(line, sizeof(line),
                "  noise: σβ %.3f deg (%s), encoder K %.2e m^½ (%s; the data alone say %.2e "
                "from %.1f degrees of freedom)\n",
                result.noise.bearing_sigma_rad * deg,
                result.bearing_sigma_estimated ? "estimated" : "given", result.noise.encoder_k,
                result.encoder_k_estimated ? "estimated, not below its floor" : "given",
                result.encoder_k_estimate, result.odometry_redundancy);
  text += line;
  if (!result.timing.statement.empty()) {
    text += "  timing (" + result.timing.treatment + "): " + result.timing.statement + "\n";
  }
  for (const BearingRunSummary& run : result.runs) {
    char kind[64];
    if (run.circular) {
      std::snprintf(kind, sizeof(kind), "circle at q = %.3f", run.q);
    } else {
      std::snprintf(kind, sizeof(kind), "not a circle at fixed q");
    }
    std::snprintf(line, sizeof(line), "  run %d: %d bearings, %s, rms residual %.3f deg\n", run.run,
                  run.bearings, kind, run.rms_residual_rad * deg);
    text += line;
  }
  for (const std::string& warning : result.warnings) text += "  warning: " + warning + "\n";
  text += StreamTimingSummary(stream_timing);
  return text;
}

}  // namespace calib
