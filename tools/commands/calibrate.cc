// `calib calibrate`: reads the log(s), calibrates, writes the contract's OUT.json and prints the
// summary.
#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/commands.h>
#include <calib/tools/commands/plot_output.h>
#include <calib/tools/commands/robot_input.h>
#include <calib/tools/report/bearing_calibration_plots.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/laser_calibration_plots.h>
#include <calib/tools/report/laser_report.h>
#include <calib/tools/report/latent_timing_report.h>
#include <calib/tools/report/robot_log_report.h>
#include <calib/tools/report/verdict.h>

#include <vector>

namespace calib::cli {
namespace {

LaserTimingOptions TimingOptions(const CalibrateOptions& flags,
                                 const LaserCalibrationOptions& options) {
  LaserTimingOptions timing;
  timing.calibration = options;
  timing.sensor_clock = flags.timing;
  return timing;
}

// The JSON and summary of a timing-aware calibration of `log`; `recording`: the bag it was made
// from, if any.
int ReportLaserStreamResult(const CalibrateOptions& flags, const LaserLog& log,
                            const LaserTimingResult& result, const Stopwatch& clock,
                            const RobotBagCalibration* bag = nullptr) {
  const RobotBagLog* recording = bag ? &bag->log : nullptr;
  const std::optional<ScanPointCalibration>* scan_points = bag ? &bag->scan_points : nullptr;
  // Refined on the scan points: their estimate is the result; the two-stage one stays beside it.
  LaserCalibrationResult calibration = result.calibration;
  if (scan_points && scan_points->has_value()) {
    calibration.estimate = (*scan_points)->estimate;
    calibration.covariance = (*scan_points)->covariance;
    calibration.stddev = (*scan_points)->stddev;
    for (std::string& w : calibration.observability.warnings) {
      w = "two-stage (before the refinement on the scan points): " + w;
    }
  }
  nlohmann::ordered_json json =
      LaserResultJson(calibration, flags.input, flags.loss, log.stream_timing);
  json["timing"]["treatment"] = "latent_times";
  json["timing"]["latent_times"] = LatentTimingJson(result);
  const NominalWheels nominal{flags.nominal_wheel_radius, flags.nominal_wheelbase};
  if (recording) json["recording"] = RobotLogJson(*recording, calibration, nominal);
  if (bag && flags.scan_points) json["scan_points"] = ScanPointJson(*bag);
  json["seconds"]["total"] = clock.Seconds();
  VerdictInputs verdict;
  verdict.converged = calibration.converged;
  verdict.warnings = calibration.observability.warnings;
  verdict.disagreements = calibration.consistency.warnings;
  verdict.streams = &log.stream_timing;
  verdict.timing_treated = true;
  if (recording) {
    verdict.warnings.insert(verdict.warnings.end(), recording->warnings.begin(),
                            recording->warnings.end());
    const std::vector<std::string> refinement = ScanPointWarnings(*bag);
    verdict.warnings.insert(verdict.warnings.end(), refinement.begin(), refinement.end());
  }
  const std::string verdict_line = AddVerdict(JudgeResult(verdict), &json);
  std::string summary =
      LaserResultSummary(calibration, flags.input, flags.loss, log.stream_timing) +
      (recording ? RobotLogSummary(*recording, calibration, nominal) : "") +
      (bag && flags.scan_points ? ScanPointSummary(*bag) : "") + LatentTimingSummary(result) +
      verdict_line;
  const Status plotted = AddCalibrationPlots(
      flags,
      [&] {
        return LaserTimingCalibrationPlots(log, result, calibration,
                                           {flags.nominal_wheel_radius, flags.nominal_wheelbase});
      },
      &json, &summary);
  if (!plotted.ok()) return Fail(plotted.message());
  return WriteReport(flags.output, json, summary, flags.quiet);
}

// One raw-stream log: every sample's true time is estimated with the calibration.
int CalibrateLaserStreamLog(const CalibrateOptions& flags, const LaserLog& log,
                            const LaserCalibrationOptions& options, const Stopwatch& clock) {
  const StatusOr<LaserTimingResult> result =
      CalibrateLaserStreams(log.streams, TimingOptions(flags, options));
  if (!result.ok()) return Fail(flags.input + ": " + result.message());
  return ReportLaserStreamResult(flags, log, *result, clock);
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
  return ReportLaserStreamResult(flags, calibrated->log.scans.log, calibrated->result, clock,
                                 &*calibrated);
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
  options.progress = ProgressPrinter(clock, flags.quiet);
  if (IsRobotInput(flags.input)) {
    return CalibrateRobotBag(flags, options, clock);
  }
  std::vector<LaserLog> logs;
  for (const std::string& path : SplitCommas(flags.input)) {
    StatusOr<LaserLog> log = ReadLaserLog(path, *format);
    if (!log.ok()) return Fail(log.message());
    logs.push_back(std::move(log).value());
  }
  if (logs.empty()) return Fail("--input names no file");
  std::vector<const std::vector<LaserInterval>*> intervals;
  bool streams = false;
  for (const LaserLog& log : logs) {
    intervals.push_back(&log.intervals);
    streams = streams || !log.streams.sensor_poses.empty();
  }

  // Raw streams carry their own timing: the latent-time calibration models it (one log), and
  // otherwise the interval-jitter treatment for tuples does not apply to them.
  if (streams && flags.timing != "off") {
    if (logs.size() != 1) {
      return Fail("raw-stream logs are calibrated one at a time with their timing (--timing " +
                  flags.timing +
                  "); give one, or --timing off to take their stamps as "
                  "sample times");
    }
    return CalibrateLaserStreamLog(flags, logs.front(), options, clock);
  }
  options.interval_jitter = !streams;
  const StatusOr<LaserCalibrationResult> result = CalibrateLaserJoint(intervals, options);
  if (!result.ok()) return Fail(flags.input + ": " + result.message());

  std::vector<StreamTiming> timing;  // Of raw stream logs only.
  for (const LaserLog& log : logs) {
    timing.insert(timing.end(), log.stream_timing.begin(), log.stream_timing.end());
  }
  nlohmann::ordered_json json = LaserResultJson(*result, flags.input, flags.loss, timing);
  json["seconds"]["total"] = clock.Seconds();
  VerdictInputs verdict;
  verdict.converged = result->converged;
  verdict.warnings = result->observability.warnings;
  verdict.disagreements = result->consistency.warnings;
  verdict.streams = &timing;
  std::string summary = LaserResultSummary(*result, flags.input, flags.loss, timing) +
                        AddVerdict(JudgeResult(verdict), &json);
  const Status plotted = AddCalibrationPlots(
      flags, [&] { return LaserCalibrationPlots(intervals, *result); }, &json, &summary);
  if (!plotted.ok()) return Fail(plotted.message());
  return WriteReport(flags.output, json, summary, flags.quiet);
}

int CalibrateBearingLog(const CalibrateOptions& flags) {
  const Stopwatch clock;
  StatusOr<BearingInput> input = ReadBearingInput(flags);
  if (!input.ok()) return Fail(input.message());
  input->calibration.progress = ProgressPrinter(clock, flags.quiet);
  const StatusOr<BearingCalibrationResult> result =
      CalibrateBearing(input->log, input->calibration);
  if (!result.ok()) return Fail(result.message());

  const std::vector<StreamTiming>& timing = input->log.stream_timing;
  nlohmann::ordered_json json = BearingResultJson(*result, flags.input, flags.loss, timing);
  json["seconds"]["total"] = clock.Seconds();
  VerdictInputs verdict;
  verdict.converged = result->converged;
  verdict.warnings = result->warnings;
  verdict.streams = &timing;
  verdict.timing_treated = true;  // Offset and stamp jitter are modelled (calibrate_bearing).
  std::string summary = BearingResultSummary(*result, flags.input, flags.loss, timing) +
                        AddVerdict(JudgeResult(verdict), &json);
  const Status plotted = AddCalibrationPlots(
      flags, [&] { return BearingCalibrationPlots(input->log, *result); }, &json, &summary);
  if (!plotted.ok()) return Fail(plotted.message());
  return WriteReport(flags.output, json, summary, flags.quiet);
}

}  // namespace

int RunCalibrate(const CalibrateOptions& options) {
  const Status given = CheckInputAndOutput(options.input, options.output);
  if (!given.ok()) return Fail(given.message());
  const Status plot_format =
      options.plots_dir.empty() ? Status::Ok() : CheckPlotFormat(options.plot_format);
  if (!plot_format.ok()) return Fail(plot_format.message());
  return IsBearingInput(options.input, options.format) ? CalibrateBearingLog(options)
                                                       : CalibrateLaserLogs(options);
}

}  // namespace calib::cli
