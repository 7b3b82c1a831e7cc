// `calib calibrate`: reads the log(s), calibrates, writes the contract's OUT.json and prints the
// summary.
#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/commands.h>
#include <calib/tools/commands/laser_input.h>
#include <calib/tools/commands/plot_output.h>
#include <calib/tools/commands/robot_input.h>
#include <calib/tools/report/bearing_calibration_plots.h>
#include <calib/tools/report/calibration_report.h>
#include <calib/tools/report/deployment.h>
#include <calib/tools/report/laser_calibration_plots.h>

#include <cmath>
#include <vector>

namespace calib::cli {
namespace {

// The driver's wheels, when --nominal_wheel_radius and --nominal_wheelbase give them.
std::optional<OdometryParams> NominalOdometry(const CalibrateOptions& flags) {
  if (!(flags.nominal_wheel_radius > 0.0 && flags.nominal_wheelbase > 0.0)) return std::nullopt;
  return OdometryParams{flags.nominal_wheel_radius, flags.nominal_wheel_radius,
                        flags.nominal_wheelbase};
}

// --export: the deployment files beside the JSON, named in it and in the summary.
Status ExportDeployment(const CalibrateOptions& flags, const StatusOr<Deployment>& deployment,
                        nlohmann::ordered_json* json, std::string* summary) {
  if (flags.export_formats.empty()) return Status::Ok();
  CALIB_RETURN_IF_ERROR(deployment.status());
  CALIB_ASSIGN_OR_RETURN(const std::vector<std::string> formats,
                         ParseExportFormats(flags.export_formats));
  CALIB_ASSIGN_OR_RETURN(const std::vector<std::string> paths,
                         WriteDeployment(*deployment, formats, flags.output));
  (*json)["exports"] = paths;
  std::string line = "  deploy:";
  for (const std::string& path : paths) line += " " + path;
  *summary += line + "\n";
  return Status::Ok();
}

// The report's last steps: the exports, then the JSON and the summary. The offset to deploy is
// the one --time_offset applied plus what the calibration still found.
int Finish(const CalibrateOptions& flags, StatusOr<Deployment> deployment,
           nlohmann::ordered_json* json, std::string summary) {
  if (deployment.ok() && flags.time_offset_s && deployment->offset_expressible) {
    deployment->time_offset_s = *flags.time_offset_s + deployment->time_offset_s.value_or(0.0);
  }
  const Status exported = ExportDeployment(flags, deployment, json, &summary);
  if (!exported.ok()) return Fail(exported.message());
  return WriteReport(flags.output, *json, summary, flags.quiet);
}

LaserTimingOptions TimingOptions(const CalibrateOptions& flags,
                                 const LaserCalibrationOptions& options) {
  LaserTimingOptions timing;
  timing.calibration = options;
  timing.sensor_clock = flags.timing;
  return timing;
}

LaserReportOptions ReportOptions(const CalibrateOptions& flags,
                                 const LaserCalibrationOptions& options) {
  LaserReportOptions report;
  report.input = flags.input;
  report.loss = flags.loss;
  report.nominal = NominalOdometry(flags);
  report.screen = options;
  report.scan_points = flags.scan_points;
  return report;
}

// The JSON and summary of a timing-aware calibration of `log`; `bag`: the recording it was made
// from, if any.
int ReportLaserStreamResult(const CalibrateOptions& flags, const LaserCalibrationOptions& options,
                            const LaserLog& log, const LaserTimingResult& result,
                            const Stopwatch& clock, const RobotBagCalibration* bag = nullptr) {
  CalibrationReport report = LaserTimingReport(result, log, bag, ReportOptions(flags, options));
  report.json["seconds"]["total"] = clock.Seconds();
  const LaserCalibrationResult& calibration = report.laser;
  const Status plotted = AddCalibrationPlots(
      flags,
      [&] {
        return LaserTimingCalibrationPlots(log, result, calibration,
                                           {flags.nominal_wheel_radius, flags.nominal_wheelbase});
      },
      &report.json, &report.summary);
  if (!plotted.ok()) return Fail(plotted.message());
  const ScanPointCalibration* refined =
      bag && bag->scan_points.has_value() ? &*bag->scan_points : nullptr;
  return Finish(
      flags, LaserDeployment(calibration, flags.input, bag ? &bag->log : nullptr, &result, refined),
      &report.json, report.summary);
}

// One raw-stream log: every sample's true time is estimated with the calibration.
int CalibrateLaserStreamLog(const CalibrateOptions& flags, const LaserLog& log,
                            const LaserCalibrationOptions& options, const Stopwatch& clock) {
  const StatusOr<LaserTimingResult> result =
      CalibrateLaserStreams(log.streams, TimingOptions(flags, options));
  if (!result.ok()) return Fail(flags.input + ": " + result.message());
  return ReportLaserStreamResult(flags, options, log, *result, clock);
}

// A robot's bag (or a directory of scans.csv and odometry.csv): its scans are matched into
// sensor poses and calibrated with their timing.
int CalibrateRobotBag(const CalibrateOptions& flags, const LaserCalibrationOptions& options,
                      const Stopwatch& clock) {
  const StatusOr<RobotInput> input = ReadRobotInput(flags);
  if (!input.ok()) return Fail(input.message());
  const StatusOr<RobotBagCalibration> calibrated =
      CalibrateRobotMessages(input->bag, input->options, TimingOptions(flags, options));
  if (!calibrated.ok()) return Fail(calibrated.message());
  return ReportLaserStreamResult(flags, options, calibrated->log.scans.log, calibrated->result,
                                 clock, &*calibrated);
}

int CalibrateLaserLogs(const CalibrateOptions& flags) {
  const StatusOr<LaserFormat> format = ParseLaserFormat(flags.format);
  if (!format.ok()) return Fail(format.message());
  const StatusOr<RobustLoss> loss = ParseLossFlags(flags.loss, flags.loss_scale);
  if (!loss.ok()) return Fail(loss.message());
  const Status timing_flag = CheckTimingFlag(flags.timing);
  if (!timing_flag.ok()) return Fail(timing_flag.message());
  const Stopwatch clock;
  LaserCalibrationOptions options;
  options.refinement.loss = *loss;
  options.refinement.loss_scale = flags.loss_scale;
  if (!(flags.redescending_scale >= 0.0) || !std::isfinite(flags.redescending_scale)) {
    return Fail("--redescending_scale must be 0 (off) or a positive number");
  }
  options.refinement.redescending_scale = flags.redescending_scale;
  options.progress = ProgressPrinter(clock, flags.quiet);
  if (IsRobotInput(flags.input)) {
    return CalibrateRobotBag(flags, options, clock);
  }
  StatusOr<std::vector<LaserLog>> read_logs = ReadLaserLogs(flags, *format);
  if (!read_logs.ok()) return Fail(read_logs.message());
  const std::vector<LaserLog>& logs = *read_logs;
  std::vector<const std::vector<LaserInterval>*> intervals;
  bool streams = false;
  for (const LaserLog& log : logs) {
    intervals.push_back(&log.intervals);
    streams = streams || !log.streams.sensor_poses.empty();
  }
  options.interval_jitter = !streams;
  LaserReportOptions report_options = ReportOptions(flags, options);
  // The screen needs the log and the calibration's closed forms: its thread starts before the
  // input checks and waits for them (on a log the checks refuse, it is released, waited for and
  // dropped).
  const bool latent_timing = streams && flags.timing != "off";
  ScreenClosedForms closed_forms;  // After report_options: released before the screen is awaited.
  if (logs.size() == 1 && !latent_timing) {
    report_options.calibration_closed_forms = closed_forms.future();
    options.closed_forms_done = closed_forms.Giver();
    report_options.started_screen = StartLaserModelScreen(logs.front().intervals, report_options);
  }
  // The checks' consensus screen is the closed form's, unless the latent-time route re-forms
  // the intervals.
  const Status checked = WithWheelUnitHint(
      CheckLaserLogs(logs, latent_timing ? nullptr : &options.consensus_screen), flags);
  if (!checked.ok()) return Fail(checked.message());

  // Raw streams carry their own timing: the latent-time calibration models it (one log), and
  // otherwise the interval-jitter treatment for tuples does not apply to them.
  if (latent_timing) {
    if (logs.size() != 1) {
      return Fail("raw-stream logs are calibrated one at a time with their timing (--timing " +
                  flags.timing +
                  "); give one, or --timing off to take their stamps as "
                  "sample times");
    }
    return CalibrateLaserStreamLog(flags, logs.front(), options, clock);
  }
  const StatusOr<LaserCalibrationResult> result = CalibrateLaserJoint(intervals, options);
  if (!result.ok()) return Fail(flags.input + ": " + result.message());

  std::vector<const LaserLog*> read;
  for (const LaserLog& log : logs) read.push_back(&log);
  CalibrationReport report = LaserIntervalReport(*result, read, report_options);
  report.json["seconds"]["total"] = clock.Seconds();
  const Status plotted = AddCalibrationPlots(
      flags, [&] { return LaserCalibrationPlots(intervals, *result); }, &report.json,
      &report.summary);
  if (!plotted.ok()) return Fail(plotted.message());
  return Finish(flags, LaserDeployment(*result, flags.input), &report.json, report.summary);
}

int CalibrateBearingLog(const CalibrateOptions& flags) {
  const Stopwatch clock;
  StatusOr<BearingInput> input = ReadBearingInput(flags);
  if (!input.ok()) return Fail(input.message());
  input->calibration.progress = ProgressPrinter(clock, flags.quiet);
  const StatusOr<BearingCalibrationResult> result =
      CalibrateBearing(input->log, input->calibration);
  if (!result.ok()) return Fail(result.message());

  CalibrationReport report = BearingCalibrationReport(*result, input->log, flags.input, flags.loss);
  report.json["seconds"]["total"] = clock.Seconds();
  const Status plotted = AddCalibrationPlots(
      flags, [&] { return BearingCalibrationPlots(input->log, *result); }, &report.json,
      &report.summary);
  if (!plotted.ok()) return Fail(plotted.message());
  return Finish(flags, BearingDeployment(*result, input->log, flags.input), &report.json,
                report.summary);
}

}  // namespace

int RunCalibrate(const CalibrateOptions& options) {
  const Status given = CheckInput(options.input);
  if (!given.ok()) return Fail(given.message());
  const Status output = CheckOutputPath("output", options.output);
  if (!output.ok()) return Fail(output.message());
  if (options.time_offset_s && !std::isfinite(*options.time_offset_s)) {
    return Fail("--time_offset must be a finite number of seconds");
  }
  const StatusOr<std::vector<std::string>> exports = ParseExportFormats(options.export_formats);
  if (!exports.ok()) return Fail(exports.message());
  const Status plot_format =
      options.plots_dir.empty() ? Status::Ok() : CheckPlotFormat(options.plot_format);
  if (!plot_format.ok()) return Fail(plot_format.message());
  return IsBearingInput(options.input, options.format) ? CalibrateBearingLog(options)
                                                       : CalibrateLaserLogs(options);
}

}  // namespace calib::cli
