// `calib calibrate`: reads the log(s), calibrates, writes the contract's OUT.json and prints the
// summary.
#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/commands.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/laser_report.h>
#include <calib/tools/report/verdict.h>

#include <vector>

namespace calib::cli {
namespace {

int CalibrateLaserLogs(const CalibrateOptions& flags) {
  const StatusOr<LaserFormat> format = ParseLaserFormat(flags.format);
  if (!format.ok()) return Fail(format.message());
  const StatusOr<RobustLoss> loss = ParseLossFlags(flags.loss, flags.loss_scale);
  if (!loss.ok()) return Fail(loss.message());
  const Stopwatch clock;
  std::vector<LaserLog> logs;
  for (const std::string& path : SplitCommas(flags.input)) {
    StatusOr<LaserLog> log = ReadLaserLog(path, *format);
    if (!log.ok()) return Fail(log.message());
    logs.push_back(std::move(log).value());
  }
  if (logs.empty()) return Fail("--input names no file");
  std::vector<const std::vector<LaserInterval>*> intervals;
  for (const LaserLog& log : logs) intervals.push_back(&log.intervals);

  LaserCalibrationOptions options;
  options.refinement.loss = *loss;
  options.refinement.loss_scale = flags.loss_scale;
  options.progress = ProgressPrinter(clock, flags.quiet);
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
  const std::string verdict_line = AddVerdict(JudgeResult(verdict), &json);
  return WriteReport(flags.output, json,
                     LaserResultSummary(*result, flags.input, flags.loss, timing) + verdict_line,
                     flags.quiet);
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
  const std::string verdict_line = AddVerdict(JudgeResult(verdict), &json);
  return WriteReport(flags.output, json,
                     BearingResultSummary(*result, flags.input, flags.loss, timing) + verdict_line,
                     flags.quiet);
}

}  // namespace

int RunCalibrate(const CalibrateOptions& options) {
  const Status given = CheckInputAndOutput(options.input, options.output);
  if (!given.ok()) return Fail(given.message());
  return IsBearingInput(options.input, options.format) ? CalibrateBearingLog(options)
                                                       : CalibrateLaserLogs(options);
}

}  // namespace calib::cli
