#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/laser/laser_model_screen.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/calibration_report.h>
#include <calib/tools/report/drift_report.h>
#include <calib/tools/report/laser_report.h>
#include <calib/tools/report/latent_timing_report.h>
#include <calib/tools/report/robot_log_report.h>
#include <calib/tools/report/verdict.h>

#include <optional>
#include <system_error>
#include <utility>

namespace calib {
namespace {

// The screen runs beside the calibration, which keeps the other core busy: on one thread (split,
// its passes waited on halves queued behind the calibration's). Run in turn, the same way, so
// that both give the same figures.
LaserCalibrationOptions ScreenOptions(const LaserReportOptions& options) {
  LaserCalibrationOptions screen = options.screen;
  screen.refinement.num_threads = 1;
  screen.closed_forms_done = nullptr;  // The calibration's hand-off, not the screen's.
  return screen;
}

// The quick look for physics the model leaves out (laser_model_screen.h): its JSON, and its
// sentence for the verdict when it finds something.
// Returns a summary line when the screen did not run on a long log.
std::string ScreenModel(const std::vector<LaserInterval>& intervals,
                        const LaserReportOptions& options, bool sample_times_estimated,
                        VerdictInputs* verdict, nlohmann::ordered_json* json) {
  if (!options.screen_model) return "";
  if (static_cast<int>(intervals.size()) > options.screen_max_intervals) {
    // The screen costs about one more calibration: on long logs, diagnose is the way.
    const std::string note = "not run on " + std::to_string(intervals.size()) +
                             " intervals (more than " +
                             std::to_string(options.screen_max_intervals) +
                             "): run `calib diagnose` to look for physics the model leaves out";
    (*json)["model_screen"]["skipped"] = note;
    return "  model screen: " + note + "\n";
  }
  const StatusOr<LaserModelScreen> screen =
      options.started_screen.valid()
          ? options.started_screen.get()
          : ScreenLaserModel(intervals, ScreenOptions(options), sample_times_estimated);
  nlohmann::ordered_json& out = (*json)["model_screen"];
  if (!screen.ok()) {
    out["error"] = screen.message();
    return "";
  }
  out["flagged"] = screen->flagged;
  out["effects"] = screen->effects;
  out["structure"] = screen->structure;
  verdict->model_screen = screen->warning;
  return "";
}

VerdictInputs LaserVerdict(const LaserCalibrationResult& result,
                           const std::vector<StreamTiming>* streams) {
  VerdictInputs verdict;
  verdict.converged = result.converged;
  verdict.warnings = result.observability.warnings;
  verdict.disagreements = result.consistency.warnings;
  verdict.unreliable = result.unreliable;
  verdict.streams = streams;
  return verdict;
}

// What the readers corrected (exact duplicates dropped, wrapped wheel angles unwrapped): first
// among the verdict's warnings; returns their summary lines.
std::string AddReaderWarnings(const std::vector<const LaserLog*>& logs, VerdictInputs* verdict) {
  std::vector<std::string> read;
  std::string lines;
  for (const LaserLog* log : logs) {
    for (const std::string& warning : log->warnings) {
      read.push_back(warning);
      lines += "  warning: " + warning + "\n";
    }
  }
  verdict->warnings.insert(verdict->warnings.begin(), read.begin(), read.end());
  return lines;
}

}  // namespace

std::shared_future<StatusOr<LaserModelScreen>> StartLaserModelScreen(
    const std::vector<LaserInterval>& intervals, const LaserReportOptions& options) {
  if (!options.screen_model || static_cast<int>(intervals.size()) > options.screen_max_intervals) {
    return {};
  }
  try {
    return std::async(
        std::launch::async, [&intervals, screen = ScreenOptions(options),
                             closed_forms = options.calibration_closed_forms]() mutable {
          // The closed forms and the convex stage are the calibration's first
          // steps: the screen checks the log, then waits for them (the other core is
          // the calibration's meanwhile) rather than computing them again. From
          // then on it keeps its core: the calibration's passes keep to theirs.
          std::optional<OccupiedCore> busy;
          if (closed_forms.valid()) {
            screen.await_closed_forms = [&closed_forms, &busy] {
              std::shared_ptr<const LaserCalibrationResult> given = closed_forms.get();
              busy.emplace();
              return given;
            };
          } else {
            busy.emplace();
          }
          return ScreenLaserModel(intervals, screen, false);
        });
  } catch (const std::system_error&) {  // No thread to be had: the report screens in turn.
    return {};
  }
}

CalibrationReport LaserIntervalReport(const LaserCalibrationResult& result,
                                      const std::vector<const LaserLog*>& logs,
                                      const LaserReportOptions& options) {
  CalibrationReport report;
  report.laser = result;
  std::vector<StreamTiming> timing;  // Of raw stream logs only.
  for (const LaserLog* log : logs) {
    timing.insert(timing.end(), log->stream_timing.begin(), log->stream_timing.end());
  }
  report.json = LaserResultJson(result, options.input, options.loss, timing);
  VerdictInputs verdict = LaserVerdict(result, &timing);
  const std::string read = AddReaderWarnings(logs, &verdict);
  const std::string screened = logs.size() == 1 ? ScreenModel(logs.front()->intervals, options,
                                                              false, &verdict, &report.json)
                                                : "";
  const DriftReport drift = LaserDrift(result, options.nominal);
  report.json["odometry_drift"] = DriftJson(drift);
  report.summary = LaserResultSummary(result, options.input, options.loss, timing) + read +
                   DriftSummary(drift) + screened + AddVerdict(JudgeResult(verdict), &report.json);
  return report;
}

CalibrationReport LaserTimingReport(const LaserTimingResult& result, const LaserLog& log,
                                    const RobotBagCalibration* bag,
                                    const LaserReportOptions& options) {
  CalibrationReport report;
  const RobotBagLog* recording = bag ? &bag->log : nullptr;
  const bool refined = bag && bag->scan_points.has_value();
  // Refined on the scan points: their estimate is the result; the two-stage one stays beside it.
  LaserCalibrationResult& calibration = report.laser;
  calibration = result.calibration;
  if (refined) {
    calibration.estimate = bag->scan_points->estimate;
    calibration.covariance = bag->scan_points->covariance;
    calibration.stddev = bag->scan_points->stddev;
    for (std::string& w : calibration.observability.warnings) {
      w = "two-stage (before the refinement on the scan points): " + w;
    }
  }
  nlohmann::ordered_json& json = report.json;
  json = LaserResultJson(calibration, options.input, options.loss, log.stream_timing);
  json["timing"]["treatment"] = "latent_times";
  json["timing"]["latent_times"] = LatentTimingJson(result);
  const NominalWheels nominal{options.nominal ? options.nominal->left_radius_m : 0.0,
                              options.nominal ? options.nominal->wheelbase_m : 0.0};
  if (recording) json["recording"] = RobotLogJson(*recording, calibration, nominal);
  if (bag && options.scan_points) json["scan_points"] = ScanPointJson(*bag);
  VerdictInputs verdict = LaserVerdict(calibration, &log.stream_timing);
  const std::string read = AddReaderWarnings({&log}, &verdict);
  verdict.timing_treated = true;
  const StatusOr<LaserLog> timed = LaserLogFromStreams(
      result.timed_streams.odometry, result.timed_streams.sensor_poses, options.input);
  const std::string screened =
      timed.ok() ? ScreenModel(timed->intervals, options, true, &verdict, &json) : "";
  if (recording) {
    verdict.warnings.insert(verdict.warnings.end(), recording->warnings.begin(),
                            recording->warnings.end());
    const std::vector<std::string> refinement = ScanPointWarnings(*bag);
    verdict.warnings.insert(verdict.warnings.end(), refinement.begin(), refinement.end());
  }
  const DriftReport drift = LaserDrift(calibration, options.nominal);
  json["odometry_drift"] = DriftJson(drift);
  const std::string verdict_line = AddVerdict(JudgeResult(verdict), &json);
  report.summary = LaserResultSummary(calibration, options.input, options.loss, log.stream_timing) +
                   (recording ? RobotLogSummary(*recording, calibration, nominal) : "") +
                   (bag && options.scan_points ? ScanPointSummary(*bag) : "") +
                   (bag && !bag->two_stage_failed.empty() ? "" : LatentTimingSummary(result)) +
                   read + DriftSummary(drift) + screened + verdict_line;
  return report;
}

CalibrationReport BearingCalibrationReport(const BearingCalibrationResult& result,
                                           const BearingLog& log, const std::string& input,
                                           const std::string& loss) {
  CalibrationReport report;
  const std::vector<StreamTiming>& timing = log.stream_timing;
  report.json = BearingResultJson(result, input, loss, timing);
  VerdictInputs verdict;
  verdict.converged = result.converged;
  verdict.warnings = log.warnings;
  verdict.warnings.insert(verdict.warnings.end(), result.warnings.begin(), result.warnings.end());
  verdict.unreliable = result.unreliable;
  verdict.streams = &timing;
  verdict.timing_treated = true;  // Offset and stamp jitter are modelled (calibrate_bearing).
  const std::optional<DriftReport> drift = BearingDrift(result, log);
  if (drift) report.json["odometry_drift"] = DriftJson(*drift);
  std::string read;  // What the reader dropped (glitches).
  for (const std::string& warning : log.warnings) read += "  warning: " + warning + "\n";
  report.summary = BearingResultSummary(result, input, loss, timing) + read +
                   (drift ? DriftSummary(*drift) : "") +
                   AddVerdict(JudgeResult(verdict), &report.json);
  return report;
}

}  // namespace calib
