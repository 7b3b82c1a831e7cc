#include <calib/tools/report/laser_report.h>
#include <calib/tools/report/robot_log_report.h>

#include <cmath>
#include <cstdio>

namespace calib {
namespace {

constexpr double kDegrees = 180.0 / 3.14159265358979323846;

std::string Format(const char* format, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char text[256];
  std::snprintf(text, sizeof(text), format, a, b, c, d);
  return text;
}

// The check of the beams' timing (beam_timing.h): the driver's, the one used, and each candidate's
// seam distance (null where it could not be judged).
nlohmann::ordered_json BeamTimingJson(const BeamTimingCheck& check) {
  nlohmann::ordered_json candidates = nlohmann::ordered_json::array();
  for (const auto& [timing, distance_m] : check.candidates) {
    candidates.push_back(
        {{"timing", timing.description},
         {"reversed", timing.reversed},
         {"time_increment_s", timing.time_increment_s},
         {"seam_distance_m", std::isfinite(distance_m) ? nlohmann::ordered_json(distance_m)
                                                       : nlohmann::ordered_json()}});
  }
  return {{"recorded", check.recorded.description},
          {"used", check.chosen.description},
          {"changed", check.changed},
          {"scans_compared", check.scans},
          {"candidates", candidates}};
}

nlohmann::ordered_json WallHeadingJson(const WallHeading& h) {
  return {{"drift", h.drift_rad},
          {"drift_stddev", h.drift_stddev_rad},
          {"drift_stddev_calibration", h.calibration_stddev_rad},
          {"scatter", h.scatter_rad}};
}

nlohmann::ordered_json WallCheckJson(const WallCheck& w) {
  nlohmann::ordered_json out = {{"right_angled", w.right_angled},
                                {"scans", w.scans},
                                {"scans_with_walls", w.scans_with_walls},
                                {"duration", w.duration_s},
                                {"calibrated", WallHeadingJson(w.calibrated)}};
  if (w.nominal) out["nominal"] = WallHeadingJson(*w.nominal);
  return out;
}

std::string WallCheckSummary(const WallCheck& w) {
  if (w.duration_s <= 0.0) return "";
  const auto heading = [](const WallHeading& h) {
    return Format("%+.1f ± %.1f° (scatter %.1f°)", kDegrees * h.drift_rad,
                  kDegrees * h.drift_stddev_rad, kDegrees * h.scatter_rad);
  };
  const std::string scans =
      std::to_string(w.scans_with_walls) + " of " + std::to_string(w.scans) + " scans";
  if (!w.right_angled) {
    return "  walls: no walls meeting at right angles throughout the log (" + scans +
           " see walls; scatter " + Format("%.1f°", kDegrees * w.calibrated.scatter_rad) +
           "): the heading is not checked against them\n";
  }
  std::string out = "  walls: under the calibrated heading their direction (mod 90°) moves " +
                    heading(w.calibrated) + Format(" over %.0f s, ", w.duration_s) + scans;
  if (w.calibrated.calibration_stddev_rad > 0.0) {
    out += Format(" (the calibration's own σ moves it by ± %.1f°)",
                  kDegrees * w.calibrated.calibration_stddev_rad);
  }
  if (w.nominal) out += "; under the nominal wheels " + heading(*w.nominal);
  return out + ": a check of the heading that needs no scan matching\n";
}

}  // namespace

nlohmann::ordered_json RobotLogJson(const RobotBagLog& log, const LaserCalibrationResult& result,
                                    const NominalWheels& nominal) {
  nlohmann::ordered_json out;
  out["scan_topic"] = log.topics.scan_topic;
  out["wheel_angles"] = log.wheel_source;
  out["base_frame"] = log.base_frame;
  out["sensor_frame"] = log.sensor_frame;
  const ScanLog& s = log.scans;
  out["scan_matching"] = {{"scans", s.matching.size()},    {"failed", s.failed_matches},
                          {"segments", s.segments},        {"keyframes", s.keyframes},
                          {"passes", log.matching_passes}, {"seconds", s.matching_seconds}};
  const LaserParamVector v = result.estimate.ToVector();
  if (log.nominal_mounting) {
    const Pose2d& m = log.nominal_mounting->base_T_sensor;
    out["nominal_mounting"] = {{"source", "tf: " + log.nominal_mounting->chain},
                               {"sensor_x", m(0)},
                               {"sensor_y", m(1)},
                               {"sensor_theta", m(2)},
                               {"upside_down", log.nominal_mounting->upside_down}};
    out["mounting_minus_nominal"] = {{"sensor_x", v(3) - m(0)},
                                     {"sensor_y", v(4) - m(1)},
                                     {"sensor_theta", std::remainder(v(5) - m(2), 2 * M_PI)}};
  }
  if (nominal.wheel_radius_m > 0.0 && nominal.wheelbase_m > 0.0) {
    out["nominal_wheels"] = {{"wheel_radius", nominal.wheel_radius_m},
                             {"wheelbase", nominal.wheelbase_m}};
    // Calibrated over nominal: what to multiply the driver's values by.
    out["corrections"] = {{"r_l", v(0) / nominal.wheel_radius_m},
                          {"r_r", v(1) / nominal.wheel_radius_m},
                          {"b", v(2) / nominal.wheelbase_m}};
  }
  if (log.beam_timing) out["beam_timing"] = BeamTimingJson(*log.beam_timing);
  if (log.walls) out["walls"] = WallCheckJson(*log.walls);
  out["warnings"] = log.warnings;
  out["notes"] = log.notes;
  return out;
}

std::string RobotLogSummary(const RobotBagLog& log, const LaserCalibrationResult& result,
                            const NominalWheels& nominal) {
  const ScanLog& s = log.scans;
  const std::string frame = log.sensor_frame.empty() ? "" : " (" + log.sensor_frame + ")";
  std::string out = "  recording: scans " + log.topics.scan_topic + frame + ", wheel angles " +
                    log.wheel_source + "\n";
  out += "  scan matching: " + std::to_string(s.matching.size()) + " scans, " +
         std::to_string(s.failed_matches) + " failed, " + std::to_string(s.keyframes) +
         " keyframes, " + std::to_string(s.segments) + " segment(s)" +
         Format(", %.2f s", s.matching_seconds) +
         (log.matching_passes > 1
              ? "; " + std::to_string(log.matching_passes) +
                    " passes, each de-skewed through the previous one's calibration\n"
              : "\n");
  const LaserParamVector v = result.estimate.ToVector();
  if (log.nominal_mounting) {
    const Pose2d& m = log.nominal_mounting->base_T_sensor;
    out += "  mounting from tf (" + log.nominal_mounting->chain + "): " +
           Format("x %.1f mm, y %.1f mm, θ %.2f°", 1e3 * m(0), 1e3 * m(1), kDegrees * m(2)) +
           Format("; calibrated − tf: x %+.1f mm, y %+.1f mm, θ %+.2f°\n", 1e3 * (v(3) - m(0)),
                  1e3 * (v(4) - m(1)), kDegrees * std::remainder(v(5) - m(2), 2 * M_PI));
  }
  if (nominal.wheel_radius_m > 0.0 && nominal.wheelbase_m > 0.0) {
    out += Format("  against the nominal wheels: r_l × %.5f, r_r × %.5f, b × %.5f\n",
                  v(0) / nominal.wheel_radius_m, v(1) / nominal.wheel_radius_m,
                  v(2) / nominal.wheelbase_m);
  }
  if (log.walls) out += WallCheckSummary(*log.walls);
  for (const std::string& n : log.notes) out += "  note: " + n + "\n";
  for (const std::string& w : log.warnings) out += "  warning: " + w + "\n";
  return out;
}

nlohmann::ordered_json ScanPointJson(const RobotBagCalibration& bag) {
  if (!bag.scan_points) return {{"refined", false}, {"warnings", bag.scan_point_warnings}};
  const ScanPointCalibration& r = *bag.scan_points;
  const LaserCalibrationResult& two_stage = bag.result.calibration;
  const LaserParamVector moved =
      (r.estimate.ToVector() - two_stage.estimate.ToVector()).cwiseQuotient(two_stage.stddev);
  nlohmann::ordered_json json = {{"refined", true},
                                 {"estimate", LaserParamJson(r.estimate.ToVector())},
                                 {"stddev", LaserParamJson(r.stddev)}};
  if (!bag.two_stage_failed.empty()) {
    json["two_stage_failed"] = bag.two_stage_failed;  // The result is the scan points' alone.
  } else {
    json["two_stage_estimate"] = LaserParamJson(two_stage.estimate.ToVector());
    json["two_stage_stddev"] = LaserParamJson(two_stage.stddev);
    json["moved_in_two_stage_sigmas"] = LaserParamJson(moved);
  }
  json.update(nlohmann::ordered_json{{"time_offset", r.time_offset_s},
                                     {"time_offset_stddev", r.time_offset_stddev_s},
                                     {"pairs", r.pairs},
                                     {"lines", r.lines},
                                     {"rounds", r.rounds},
                                     {"converged", r.converged},
                                     {"range_sigma", r.range_sigma_m},
                                     {"inlier_fraction", r.inlier_fraction},
                                     {"correlation_inflation", r.correlation_inflation},
                                     {"seconds", r.seconds},
                                     {"warnings", r.warnings}});
  return json;
}

std::string ScanPointSummary(const RobotBagCalibration& bag) {
  if (!bag.scan_points) {
    std::string out;
    for (const std::string& w : bag.scan_point_warnings) out += "  warning: " + w + "\n";
    return out;
  }
  const ScanPointCalibration& r = *bag.scan_points;
  const LaserCalibrationResult& two_stage = bag.result.calibration;
  const LaserParamVector moved =
      (r.estimate.ToVector() - two_stage.estimate.ToVector()).cwiseQuotient(two_stage.stddev);
  std::string out =
      "  refined on the scan points (the estimate above): " + std::to_string(r.pairs) +
      " scan pairs, " + std::to_string(r.lines) + " point-to-line distances" +
      Format(", σ̂ %.1f mm, %.0f %% inliers, %.1f s;", 1e3 * r.range_sigma_m,
             100.0 * r.inlier_fraction, r.seconds) +
      Format(" the beams' times %+.2f ± %.2f ms beyond the ", 1e3 * r.time_offset_s,
             1e3 * r.time_offset_stddev_s) +
      (bag.two_stage_failed.empty() ? "timing's;" : "stamps;");
  if (bag.two_stage_failed.empty()) {
    out += " moved from the two-stage estimate by";
    for (int i = 0; i < kNumLaserParams; ++i) {
      out += (i ? ", " : " ") + kLaserParamNames[i] + Format(" %+.1fσ", moved(i));
    }
  } else {
    out += " the two-stage route could not calibrate, the result is the scan points' alone";
  }
  out += "\n";
  for (const std::string& w : r.warnings) out += "  warning: " + w + "\n";
  return out;
}

std::vector<std::string> ScanPointWarnings(const RobotBagCalibration& bag) {
  std::vector<std::string> out = bag.scan_point_warnings;
  if (bag.scan_points) {
    out.insert(out.end(), bag.scan_points->warnings.begin(), bag.scan_points->warnings.end());
  }
  return out;
}

}  // namespace calib
