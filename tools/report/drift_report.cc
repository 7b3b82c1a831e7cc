#include <calib/tools/report/drift_report.h>

#include <cstdio>

namespace calib {
namespace {

nlohmann::ordered_json Json(const OdometryDrift& d) {
  return {{"distance_mm_per_m", d.distance_mm_per_m},
          {"heading_deg_per_m", d.heading_deg_per_m},
          {"turn_deg_per_turn", d.turn_deg_per_turn}};
}

std::string Words(const OdometryDrift& d, const char* sign) {
  char text[160];
  std::snprintf(text, sizeof(text),
                "%s%.2g mm per m travelled, %s%.2g° per m straight, %s%.2g° per turn on the spot",
                sign, d.distance_mm_per_m, sign, d.heading_deg_per_m, sign, d.turn_deg_per_turn);
  return text;
}

}  // namespace

DriftReport LaserDrift(const LaserCalibrationResult& result,
                       const std::optional<OdometryParams>& nominal) {
  DriftReport report;
  const OdometryParams& calibrated = result.estimate.odometry;
  report.calibrated_1sigma =
      DriftFromUncertainty(calibrated, result.covariance.topLeftCorner<3, 3>());
  if (nominal) report.nominal = DriftOf(*nominal, calibrated);
  return report;
}

std::optional<DriftReport> BearingDrift(const BearingCalibrationResult& result,
                                        const BearingLog& log) {
  if (!result.has_metric) return std::nullopt;
  const double r = log.meta.wheel_radius_m, b = log.meta.wheelbase_m;
  const BearingMetricParams& m = result.metric;
  const OdometryParams calibrated{r * m.delta_l, r * m.delta_r, b * m.delta_b};
  // (r_l, r_r, b) from the metric set (φ, ψ, ρ, δR, δL, δB).
  Eigen::Matrix<double, 3, kNumBearingMetricParams> jacobian =
      Eigen::Matrix<double, 3, kNumBearingMetricParams>::Zero();
  jacobian(0, 4) = r;
  jacobian(1, 3) = r;
  jacobian(2, 5) = b;
  DriftReport report;
  report.calibrated_1sigma =
      DriftFromUncertainty(calibrated, jacobian * result.metric_covariance * jacobian.transpose());
  report.nominal = DriftOf(OdometryParams{r, r, b}, calibrated);
  return report;
}

nlohmann::ordered_json DriftJson(const DriftReport& report) {
  nlohmann::ordered_json out;
  out["calibrated_1sigma"] = Json(report.calibrated_1sigma);
  if (report.nominal) out["nominal"] = Json(*report.nominal);
  return out;
}

std::string DriftSummary(const DriftReport& report) {
  std::string out =
      "  odometry drift with this calibration (1σ): " + Words(report.calibrated_1sigma, "±") + "\n";
  if (report.nominal) {
    out += "  odometry drift with the nominal wheels: " + Words(*report.nominal, "") + "\n";
  }
  return out;
}

}  // namespace calib
