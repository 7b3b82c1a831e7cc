#include <calib/core/text_format.h>
#include <calib/solvers/bearing/bearing_dead_reckoning.h>
#include <calib/tools/report/bearing_calibration_plots.h>
#include <calib/tools/report/residual_panels.h>
#include <calib/tools/report/svg_chart.h>

#include <cmath>
#include <string>
#include <vector>

namespace calib {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

std::string LengthUnit(const BearingPaths& paths) { return paths.metric ? "m" : "nominal m"; }

// Whether bearing j of run i is an inlier (true when the result does not say).
bool Used(const BearingCalibrationResult& result, size_t i, int j) {
  if (j < 0 || i >= result.is_inlier.size()) return true;
  const std::vector<bool>& run = result.is_inlier[i];
  return static_cast<size_t>(j) < run.size() ? static_cast<bool>(run[j]) : true;
}

std::string PathsSvg(const BearingPaths& paths) {
  const std::string unit = LengthUnit(paths);
  ChartFigure figure;
  figure.title = "Robot paths: dead reckoning before and after calibration";
  figure.caption = {
      "One panel per run, seen from above in the landmark's frame (the landmark is the white "
      "dot at the origin), lengths in " +
      unit +
      (paths.metric ? ""
                    : " (no initial distance, so the bearings do not fix the scale: a nominal "
                      "metre is the right wheel's travel at meta.json's radius)") +
      ". Black: the path the bundle adjustment fits to the bearings and encoders together. "
      "Orange, dashed: dead reckoning from the same start with the nominal wheels "
      "(meta.json's radius and wheelbase). Green: the same with the calibrated wheels."};
  for (const BearingRunPaths& run : paths.runs) {
    ChartPanel panel;
    panel.title = Format("Run %d", run.run);
    panel.x_label = "x [" + unit + "]";
    panel.y_label = "y [" + unit + "]";
    panel.equal_aspect = true;
    panel.series = {
        PathSeries("bundle adjustment", run.adjusted, kReferenceColor, ChartStyle::kLine),
        PathSeries("calibrated", run.calibrated, kCalibratedColor, ChartStyle::kLine),
        PathSeries("nominal wheels", run.nominal, kBeforeColor, ChartStyle::kDashedLine)};
    ChartSeries landmark{"landmark", {0.0}, {0.0}};
    landmark.style = ChartStyle::kStar;
    landmark.color = "#ffffff";
    panel.series.push_back(landmark);
    const double old_gap = (run.nominal.back().head<2>() - run.adjusted.back().head<2>()).norm();
    const double new_gap = (run.calibrated.back().head<2>() - run.adjusted.back().head<2>()).norm();
    double travelled = 0.0;
    for (size_t k = 1; k < run.adjusted.size(); ++k) {
      travelled += (run.adjusted[k].head<2>() - run.adjusted[k - 1].head<2>()).norm();
    }
    panel.note = Format("End point off by %.3f (nominal), %.3f (calibrated) %s", old_gap, new_gap,
                        paths.metric ? "m" : "nominal m");
    if (travelled < 0.05 * run.adjusted.front().head<2>().norm()) {
      panel.note += "; the robot turns in place";
    }
    figure.panels.push_back(panel);
  }
  figure.columns = std::min<int>(3, std::max<size_t>(1, paths.runs.size()));
  figure.panel_width = 360;
  figure.panel_height = 320;
  return ChartSvg(figure);
}

std::string ResidualsSvg(const BearingCalibrationResult& result) {
  std::vector<double> values;
  std::vector<bool> used;
  for (size_t i = 0; i < result.residuals_rad.size(); ++i) {
    for (size_t j = 0; j < result.residuals_rad[i].size(); ++j) {
      values.push_back(result.residuals_rad[i][j] * kRadToDeg);
      used.push_back(Used(result, i, static_cast<int>(j)));
    }
  }
  const double sigma = result.noise.bearing_sigma_rad * kRadToDeg;
  ChartFigure figure;
  figure.title = "Bearing residuals after calibration";
  figure.caption = {
      "For each bearing: the measured bearing of the landmark minus the one the calibrated "
      "model predicts at the fitted pose. Blue: bearings used (inliers); red: bearings "
      "rejected as outliers (beyond √10.83 σβ). Dashed: the normal density of the fitted "
      "bearing noise σβ, scaled to the inlier count."};
  figure.panels = {ResidualHistogramPanel("Bearing residual", "bearing error [deg]", values, used,
                                          sigma, Format("σβ = %.3g deg", sigma), "bearings")};
  figure.columns = 1;
  figure.panel_width = 560;
  figure.panel_height = 320;
  return ChartSvg(figure);
}

std::string CoverageSvg(const BearingPaths& paths, const BearingCalibrationResult& result) {
  std::vector<double> v, omega;
  std::vector<bool> used;
  ChartPanel distance;
  distance.title = "Distance to the landmark";
  distance.x_label = "time from the run's start [s]";
  distance.y_label = "distance [" + LengthUnit(paths) + "]";
  const char* colors[] = {"#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02"};
  for (size_t r = 0; r < paths.runs.size(); ++r) {
    const BearingRunPaths& run = paths.runs[r];
    ChartSeries d{Format("run %d", run.run), {}, {}};
    d.color = colors[r % 6];
    for (size_t k = 0; k < run.t_s.size(); ++k) {
      d.x.push_back(run.t_s[k] - run.t_s.front());
      d.y.push_back(run.adjusted[k].head<2>().norm());
      if (k == 0) continue;
      v.push_back(run.v_mps[k]);
      omega.push_back(run.omega_radps[k] * kRadToDeg);
      used.push_back(Used(result, run.index, run.bearing[k]));
    }
    distance.series.push_back(d);
  }
  const std::string speed_unit = paths.metric ? "m/s" : "nominal m/s";
  ChartFigure figure;
  figure.title = "Motion covered by the log";
  figure.caption = {
      "Left: each step between consecutive bearings as one point at the robot's mean forward "
      "speed v and turn rate ω (calibrated wheels); dots: the bearing at its end was used, "
      "crosses: rejected as an outlier. Right: the robot's distance to the landmark along "
      "each run (the bundle adjustment's path). The calibration needs turns at several "
      "curvatures with the landmark in view."};
  figure.panels = {UsedRejectedScatter("Forward speed and turn rate between bearings",
                                       "v, forward speed [" + speed_unit + "]",
                                       "ω, turn rate [deg/s]", v, omega, used, "steps"),
                   distance};
  figure.panel_width = 420;
  figure.panel_height = 320;
  return ChartSvg(figure);
}

}  // namespace

PlotFiles BearingCalibrationPlots(const BearingLog& log, const BearingCalibrationResult& result) {
  const BearingPaths paths = BearingDeadReckoning(log, result);
  PlotFiles files;
  files.emplace_back("bearing_paths.svg", PathsSvg(paths));
  files.emplace_back("bearing_residuals.svg", ResidualsSvg(result));
  files.emplace_back("bearing_coverage.svg", CoverageSvg(paths, result));
  return files;
}

}  // namespace calib
