#include <calib/core/laser/laser_log_io.h>
#include <calib/core/text_format.h>
#include <calib/solvers/laser/laser_dead_reckoning.h>
#include <calib/tools/report/laser_calibration_plots.h>
#include <calib/tools/report/residual_panels.h>
#include <calib/tools/report/svg_chart.h>

#include <cmath>

namespace calib {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

struct Baseline {
  LaserCalibration parameters;
  std::string label;  // For the legend.
  std::string words;  // For the caption.
};

Baseline ChooseBaseline(const LaserCalibrationResult& result, const LaserPlotBaseline& given) {
  Baseline b;
  if (given.nominal_wheel_radius_m > 0.0 && given.nominal_wheelbase_m > 0.0) {
    b.parameters.odometry = {given.nominal_wheel_radius_m, given.nominal_wheel_radius_m,
                             given.nominal_wheelbase_m};
    b.parameters.base_T_sensor = result.estimate.base_T_sensor;
    b.label = "nominal wheels";
    b.words = Format("the nominal wheels (r = %.1f mm, b = %.1f mm, with the calibrated mounting)",
                     given.nominal_wheel_radius_m * 1e3, given.nominal_wheelbase_m * 1e3);
    return b;
  }
  b.parameters =
      (result.seed_trimmed ? result.closed_form_trimmed : result.closed_form).calibration;
  b.label = "closed-form seed";
  b.words =
      "the closed-form seed (Censi's closed form, wheels and mounting; the log has no nominal "
      "values)";
  return b;
}

std::vector<bool> InlierFlags(const LaserCalibrationResult& result, size_t log,
                              const std::vector<Eigen::Vector3d>& errors) {
  if (log < result.is_inlier.size() && result.is_inlier[log].size() == errors.size()) {
    return result.is_inlier[log];
  }
  if (log < result.noise_sigma.size()) return ClassifyLaserInliers(errors, result.noise_sigma[log]);
  return std::vector<bool>(errors.size(), true);
}

// The gap between a dead-reckoned path and the scan-matched one against the distance the sensor
// travelled.
ChartSeries GapSeries(const std::string& label, const std::vector<Pose2d>& path,
                      const std::vector<Pose2d>& reference, const char* color, ChartStyle style) {
  ChartSeries s{label, {}, {}};
  double travelled = 0.0;
  for (size_t k = 0; k < path.size() && k < reference.size(); ++k) {
    if (k > 0) travelled += (reference[k].head<2>() - reference[k - 1].head<2>()).norm();
    s.x.push_back(travelled);
    s.y.push_back((path[k].head<2>() - reference[k].head<2>()).norm());
  }
  s.color = color;
  s.style = style;
  return s;
}

std::string PathsSvg(const std::vector<LaserInterval>& intervals,
                     const LaserCalibrationResult& result, const Baseline& before,
                     const std::vector<bool>& used) {
  const LaserPathComparison compared =
      CompareLaserPaths(intervals, before.parameters, result.estimate, used);
  const std::vector<Pose2d>& sensor = compared.scan_matched;
  const std::vector<Pose2d>& old_path = compared.before;
  const std::vector<Pose2d>& new_path = compared.calibrated;
  ChartPanel paths;
  paths.title = "Sensor path seen from above";
  paths.x_label = "x [m] (sensor frame at the start)";
  paths.y_label = "y [m] (sensor frame at the start)";
  paths.equal_aspect = true;
  // The "before" path last: it stays visible where it coincides with the calibrated one.
  paths.series = {PathSeries("scan matching", sensor, kReferenceColor, ChartStyle::kLine),
                  PathSeries("calibrated", new_path, kCalibratedColor, ChartStyle::kLine),
                  PathSeries(before.label, old_path, kBeforeColor, ChartStyle::kDashedLine)};
  ChartSeries start{"start", {0.0}, {0.0}};
  start.style = ChartStyle::kStar;
  start.color = "#ffffff";
  paths.series.push_back(start);

  ChartPanel gaps;
  gaps.title = "Distance from the scan-matched path";
  gaps.x_label = "distance travelled by the sensor [m]";
  gaps.y_label = "position gap [m]";
  gaps.series = {GapSeries("calibrated", new_path, sensor, kCalibratedColor, ChartStyle::kLine),
                 GapSeries(before.label, old_path, sensor, kBeforeColor, ChartStyle::kDashedLine)};
  gaps.note =
      Format("At the end: %s %.3f m off, calibrated %.3f m off, over %.1f m", before.label.c_str(),
             gaps.series[1].y.back(), gaps.series[0].y.back(), gaps.series[0].x.back());

  ChartFigure figure;
  figure.title = "Dead reckoning before and after calibration, over the sensor's own path";
  figure.caption = {
      "All paths are the sensor's, in its frame at the start of the log (x forward, y left). "
      "Black: the scan matcher's displacements chained. Orange, dashed: the wheel odometry "
      "with " +
          before.words +
          ", carried to the sensor through the mounting and chained. Green: the same with the "
          "calibrated wheels and mounting. Intervals rejected as outliers (a bad scan match or "
          "a slip) take the calibrated displacement in all three paths, so that they show as "
          "drift in none.",
      "Right: how far each dead-reckoned path is from the scan-matched one as the sensor "
      "travels. Part of the gap is the scan matcher's own random walk, common to both; wrong "
      "wheels add a drift that grows with the distance. A closed-form seed is often close to the "
      "calibration, and then so are their paths."};
  figure.panels = {paths, gaps};
  figure.panel_width = 460;
  figure.panel_height = 380;
  return ChartSvg(figure);
}

std::string ResidualsSvg(const std::vector<Eigen::Vector3d>& errors, const std::vector<bool>& used,
                         const Eigen::Vector3d& sigma, const std::string& note) {
  const char* titles[3] = {"Forward (x) residual", "Sideways (y) residual", "Heading (θ) residual"};
  const char* labels[3] = {"x error [mm]", "y error [mm]", "θ error [mrad]"};
  const char* units[3] = {"mm", "mm", "mrad"};
  ChartFigure figure;
  figure.title = "Scan-matching residuals after calibration";
  figure.caption = {
      "For each interval: the sensor displacement the scan matcher measured minus the one the "
      "calibrated wheels and mounting predict, in the sensor frame at the interval start. "
      "Blue: intervals used (inliers); red: intervals rejected as outliers (squared whitened "
      "residual above the χ² cut of 16.3). Dashed: the normal density of the noise σ fitted "
      "to the inliers, scaled to their count; bars that follow it mean the noise model fits."};
  if (!note.empty()) figure.caption.push_back(note);
  for (int c = 0; c < 3; ++c) {
    std::vector<double> values;
    for (const Eigen::Vector3d& e : errors) values.push_back(e(c) * 1e3);
    figure.panels.push_back(
        ResidualHistogramPanel(titles[c], labels[c], values, used, sigma(c) * 1e3,
                               Format("σ = %.3g %s", sigma(c) * 1e3, units[c]), "intervals"));
  }
  figure.columns = 3;
  figure.panel_width = 340;
  figure.panel_height = 260;
  return ChartSvg(figure);
}

std::string CoverageSvg(const std::vector<LaserInterval>& intervals,
                        const LaserCalibrationResult& result, const std::vector<bool>& used) {
  std::vector<double> v, omega;
  for (const Eigen::Vector2d& s : IntervalRobotSpeeds(intervals, result.estimate.odometry)) {
    v.push_back(s(0));
    omega.push_back(s(1) * kRadToDeg);
  }
  ChartFigure figure;
  figure.title = "Motion covered by the log";
  figure.caption = {
      "Each interval is one point at the robot's mean forward speed v and turn rate ω over it "
      "(calibrated wheels). Dots: intervals used; crosses: intervals rejected as outliers. "
      "All six parameters need both turning (ω ≠ 0, both directions) and driving while "
      "turning (v and ω together); a log on one axis only leaves some of them undetermined."};
  figure.panels = {UsedRejectedScatter("Forward speed and turn rate of each interval",
                                       "v, forward speed [m/s]", "ω, turn rate [deg/s]", v, omega,
                                       used, "intervals")};
  figure.columns = 1;
  figure.panel_width = 560;
  figure.panel_height = 380;
  return ChartSvg(figure);
}

PlotFiles Plots(const std::vector<const std::vector<LaserInterval>*>& logs,
                const LaserCalibrationResult& result, const LaserPlotBaseline& baseline,
                const std::string& residual_note) {
  const Baseline before = ChooseBaseline(result, baseline);
  PlotFiles files;
  for (size_t i = 0; i < logs.size(); ++i) {
    const std::vector<LaserInterval>& intervals = *logs[i];
    if (intervals.empty()) continue;
    const std::string prefix = logs.size() > 1 ? Format("log%zu_", i + 1) : "";
    const std::vector<Eigen::Vector3d> errors = LaserIntervalErrors(intervals, result.estimate);
    const std::vector<bool> used = InlierFlags(result, i, errors);
    const Eigen::Vector3d sigma =
        i < result.noise_sigma.size() ? result.noise_sigma[i] : Eigen::Vector3d::Zero();
    files.emplace_back(prefix + "laser_paths.svg", PathsSvg(intervals, result, before, used));
    files.emplace_back(prefix + "laser_residuals.svg",
                       ResidualsSvg(errors, used, sigma, residual_note));
    files.emplace_back(prefix + "laser_coverage.svg", CoverageSvg(intervals, result, used));
  }
  return files;
}

}  // namespace

PlotFiles LaserCalibrationPlots(const std::vector<const std::vector<LaserInterval>*>& logs,
                                const LaserCalibrationResult& result,
                                const LaserPlotBaseline& baseline) {
  return Plots(logs, result, baseline, "");
}

PlotFiles LaserTimingCalibrationPlots(const LaserLog& log, const LaserTimingResult& timing,
                                      const LaserCalibrationResult& calibration,
                                      const LaserPlotBaseline& baseline) {
  const StatusOr<LaserLog> timed = LaserLogFromStreams(
      timing.timed_streams.odometry, timing.timed_streams.sensor_poses, log.source);
  const bool usable = timed.ok() && !calibration.is_inlier.empty() &&
                      calibration.is_inlier[0].size() == timed->intervals.size();
  return Plots({usable ? &timed->intervals : &log.intervals}, calibration, baseline,
               std::string("Timing-aware calibration: the intervals run between the estimated "
                           "sample times") +
                   (usable ? "" : " (not rebuilt here: shown between the stamps)") +
                   "; σ and the outlier flags are the fit's, whose sample times are latent, so "
                   "a rejected interval may sit in the bulk here.");
}

}  // namespace calib
