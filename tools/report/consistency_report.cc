#include <calib/core/text_format.h>
#include <calib/tools/report/consistency_report.h>

#include <cmath>

namespace calib {
namespace {

nlohmann::ordered_json TotalJson(const LaserConsistencyTotal& t) {
  return {{"predicted", t.predicted},
          {"measured", t.measured},
          {"difference", t.measured - t.predicted},
          {"sigma_predicted", t.sigma_predicted},
          {"sigma_measured", t.sigma_measured},
          {"sigma_ends", t.sigma_ends},
          {"sigma", t.sigma},
          {"z", t.z},
          {"p_value", t.p_value},
          {"significant", t.significant}};
}

}  // namespace

nlohmann::ordered_json LaserConsistencyJson(const LaserConsistency& c) {
  nlohmann::ordered_json windows = nlohmann::ordered_json::array();
  for (const LaserConsistencyWindow& w : c.windows) {
    windows.push_back({{"log", w.log},
                       {"kind", w.kind},
                       {"first_interval", w.first + 1},
                       {"last_interval", w.last + 1},
                       {"inliers", w.intervals},
                       {"start_s", w.start_s},
                       {"end_s", w.end_s},
                       {"rotation_rad", TotalJson(w.rotation)},
                       {"translation_m", TotalJson(w.translation)}});
  }
  return {{"checked", c.checked},
          {"note", c.note},
          {"tests", c.tests},
          {"family_alpha", LaserConsistencyOptions{}.family_alpha},
          {"lag", {{"rotation", c.rotation_lag}, {"translation", c.translation_lag}}},
          {"windows", windows},
          {"warnings", c.warnings}};
}

std::string LaserConsistencySummary(const LaserConsistency& c) {
  if (!c.checked) return "  consistency: " + c.note + "\n";
  std::string text;
  int flagged = 0;
  for (const LaserConsistencyWindow& w : c.windows) {
    flagged += w.rotation.significant || w.translation.significant;
    if (w.kind != "run") continue;
    text += Format(
        "  consistency over t = %.1f–%.1f s: rotation %.1f° predicted, %.1f° measured (z %.1f); "
        "travel %.3f m predicted, %.3f m measured (z %.1f)\n",
        w.start_s, w.end_s, w.rotation.predicted * 180.0 / M_PI, w.rotation.measured * 180.0 / M_PI,
        w.rotation.z, w.translation.predicted, w.translation.measured, w.translation.z);
  }
  text += Format("  consistency: %d of %d windows disagree beyond the family's 3σ level\n", flagged,
                 static_cast<int>(c.windows.size()));
  return text;
}

}  // namespace calib
