// `calib diagnose`: reads one log, searches for the physics the base model leaves out, writes the
// contract's OUT.json, the plots and the summary.
#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/commands.h>
#include <calib/tools/commands/laser_input.h>
#include <calib/tools/commands/plot_output.h>
#include <calib/tools/commands/robot_input.h>
#include <calib/tools/report/bearing_diagnose_report.h>
#include <calib/tools/report/deploy_advice.h>
#include <calib/tools/report/laser_diagnose_report.h>
#include <calib/tools/report/latent_timing_report.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace calib::cli {
namespace {

using Plots = std::vector<std::string>;

// The report writers of one problem's diagnosis.
template <typename Diagnosis>
struct DiagnosisWriters {
  StatusOr<Plots> (*plots)(const Diagnosis&, const std::string& directory);
  nlohmann::ordered_json (*json)(const Diagnosis&, const std::string& input, const Plots&);
  std::string (*summary)(const Diagnosis&, const std::string& input, const Plots&);
};

// `timing`: the latent-time calibration the search ran after (raw streams), or null.
template <typename Diagnosis>
int WriteDiagnosis(const DiagnoseOptions& flags, const Diagnosis& diagnosis, const Stopwatch& clock,
                   const DiagnosisWriters<Diagnosis>& writers,
                   const LaserTimingResult* timing = nullptr) {
  // Plots go beside the JSON, or where --plots_dir says; none for a summary-only run.
  const bool output_file = !flags.output.empty() && flags.output != "-";
  const std::string plots_dir = !flags.plots_dir.empty() ? flags.plots_dir
                                : output_file            ? DefaultPlotsDir(flags.output)
                                                         : "";
  Plots plots;
  if (!plots_dir.empty()) {
    StatusOr<Plots> written = writers.plots(diagnosis, plots_dir);
    if (!written.ok()) return Fail(written.message());
    plots = std::move(written).value();
    const Status rasterized = AddRasterized(flags.plot_format, &plots);
    if (!rasterized.ok()) return Fail(rasterized.message());
  }
  nlohmann::ordered_json json = writers.json(diagnosis, flags.input, plots);
  std::string summary = writers.summary(diagnosis, flags.input, plots);
  if (timing != nullptr) {
    // Timing is named first, as timing (and adopted when it changes the calibration).
    AddLatentTimingToDiagnosis(*timing, &json);
    summary += LatentTimingSummary(*timing) +
               "  timing: modelled first, as timing: the effects above were searched on the "
               "intervals between the estimated sample times\n";
  }
  const DeployAdvice advice = AdviseDeployment(json);
  json["deploy"] = advice.json;
  summary += advice.summary;
  json["seconds"] = clock.Seconds();
  return WriteReport(flags.output, json, summary, flags.quiet);
}

StatusOr<BoundaryChoice> ParseBoundarySpeeds(const std::string& name) {
  return ParseChoice<BoundaryChoice>("boundary_speeds", name,
                                     {{"auto", BoundaryChoice::kAuto},
                                      {"piecewise", BoundaryChoice::kPiecewiseConstant},
                                      {"smooth", BoundaryChoice::kSmooth}},
                                     "auto, piecewise or smooth");
}

// The laser diagnosis' options from the flags (without the progress callback).
StatusOr<LaserDiagnosisOptions> LaserOptions(const DiagnoseOptions& flags) {
  CALIB_ASSIGN_OR_RETURN(const RobustLoss loss, ParseLossFlags(flags.loss, flags.loss_scale));
  if (flags.max_effects < 0) return Status::InvalidInput("--max_effects must not be negative");
  LaserDiagnosisOptions options;
  options.calibration.refinement.loss = loss;
  options.calibration.refinement.loss_scale = flags.loss_scale;
  options.alpha = flags.family_alpha;
  options.max_effects = flags.max_effects;
  options.cv_blocks = flags.cv_blocks;
  CALIB_ASSIGN_OR_RETURN(options.boundary, ParseBoundarySpeeds(flags.boundary_speeds));
  if (!flags.candidates.empty()) {
    options.candidates.clear();
    for (const std::string& name : SplitCommas(flags.candidates)) {
      CALIB_ASSIGN_OR_RETURN(const LaserEffect effect, ParseLaserEffect(name));
      options.candidates.push_back(effect);
    }
  }
  return options;
}

// One laser log, read and checked as calibrate does.
StatusOr<LaserLog> ReadCheckedLaserLog(const DiagnoseOptions& flags, LaserFormat format) {
  CALIB_ASSIGN_OR_RETURN(std::vector<LaserLog> logs, ReadCheckedLaserLogs(flags, format));
  for (const std::string& warning : logs.front().warnings) {
    if (!flags.quiet) std::fprintf(stderr, "calib: warning: %s\n", warning.c_str());
  }
  return std::move(logs.front());
}

// A robot's recording: its scans matched into sensor poses and calibrated with their timing (as
// calibrate does), then searched like a stream directory on that timing.
StatusOr<LaserLog> RobotLaserLog(const DiagnoseOptions& flags, const LaserTimingOptions& options,
                                 std::optional<LaserTimingResult>* timing) {
  CALIB_ASSIGN_OR_RETURN(const RobotInput input, ReadRobotInput(flags));
  CALIB_ASSIGN_OR_RETURN(RobotBagCalibration calibrated,
                         CalibrateRobotMessages(input.bag, input.options, options));
  *timing = std::move(calibrated.result);
  return std::move(calibrated.log.scans.log);
}

int DiagnoseLaserLog(const DiagnoseOptions& flags) {
  const StatusOr<LaserFormat> format = ParseLaserFormat(flags.format);
  if (!format.ok()) return Fail(format.message());
  StatusOr<LaserDiagnosisOptions> options = LaserOptions(flags);
  if (!options.ok()) return Fail(options.message());
  const Stopwatch clock;
  options->progress = ProgressPrinter(clock, flags.quiet);
  LaserTimingOptions timing_options;
  timing_options.calibration = options->calibration;
  timing_options.sensor_clock = flags.timing;
  const bool robot = IsRobotInput(flags.input);
  std::optional<LaserTimingResult> timing;
  StatusOr<LaserLog> log =
      robot ? RobotLaserLog(flags, timing_options, &timing) : ReadCheckedLaserLog(flags, *format);
  if (!log.ok()) return Fail(log.message());
  // Raw streams: their timing (sample times behind the stamps, a free-running sensor clock) is
  // estimated first, and the search runs on the intervals between the estimated times, so that
  // a timing artefact is not taken for slip or a speed-dependent radius.
  if (!robot && !log->streams.sensor_poses.empty() && flags.timing != "off") {
    StatusOr<LaserTimingResult> result = CalibrateLaserStreams(log->streams, timing_options);
    if (!result.ok()) {
      return Fail(flags.input + ": the timing-aware calibration failed: " + result.message() +
                  " (--timing off searches with the stamps as sample times)");
    }
    timing = std::move(result).value();
  }
  if (timing) {
    StatusOr<LaserLog> timed = LaserLogFromStreams(timing->timed_streams.odometry,
                                                   timing->timed_streams.sensor_poses, flags.input);
    if (!timed.ok()) return Fail(flags.input + ": at the estimated times: " + timed.message());
    log->intervals = std::move(timed->intervals);
    options->sample_times_estimated = true;
  }
  const StatusOr<LaserDiagnosis> diagnosis = DiagnoseLaser(log->intervals, *options);
  if (!diagnosis.ok()) return Fail(flags.input + ": " + diagnosis.message());
  return WriteDiagnosis<LaserDiagnosis>(
      flags, *diagnosis, clock,
      {&WriteLaserDiagnosisPlots, &LaserDiagnosisJson, &LaserDiagnosisSummary},
      timing ? &*timing : nullptr);
}

// One candidate (time_offset) for the bearing problem: --candidates, --max_effects and
// --boundary_speeds concern the laser's.
int DiagnoseBearingLog(const DiagnoseOptions& flags) {
  const Stopwatch clock;
  StatusOr<BearingInput> input = ReadBearingInput(flags);
  if (!input.ok()) return Fail(input.message());
  BearingDiagnosisOptions options;
  options.calibration = input->calibration;
  options.alpha = flags.family_alpha;
  options.cv_blocks = flags.cv_blocks;
  options.progress = ProgressPrinter(clock, flags.quiet);
  const StatusOr<BearingDiagnosis> diagnosis = DiagnoseBearing(input->log, options);
  if (!diagnosis.ok()) return Fail(diagnosis.message());
  return WriteDiagnosis<BearingDiagnosis>(
      flags, *diagnosis, clock,
      {&WriteBearingDiagnosisPlots, &BearingDiagnosisJson, &BearingDiagnosisSummary});
}

}  // namespace

int RunDiagnose(const DiagnoseOptions& options) {
  const Status given = CheckInput(options.input);
  if (!given.ok()) return Fail(given.message());
  const Status output = CheckOutputPath("output", options.output);
  if (!output.ok()) return Fail(output.message());
  if (options.time_offset_s && !std::isfinite(*options.time_offset_s)) {
    return Fail("--time_offset must be a finite number of seconds");
  }
  // Bags or CSM logs given with commas are one recording; interval logs are diagnosed one by one.
  if (options.input.find(',') != std::string::npos && !IsRobotInput(options.input)) {
    return Fail("diagnose takes one log (--input names several)");
  }
  if (!(options.family_alpha > 0.0 && options.family_alpha < 1.0)) {
    return Fail("--family_alpha must be in (0, 1)");
  }
  if (options.cv_blocks < 2) return Fail("--cv_blocks must be at least 2");
  const Status timing = CheckTimingFlag(options.timing);
  if (!timing.ok()) return Fail(timing.message());
  const Status plot_format = CheckPlotFormat(options.plot_format);
  if (!plot_format.ok()) return Fail(plot_format.message());
  return IsBearingInput(options.input, options.format) ? DiagnoseBearingLog(options)
                                                       : DiagnoseLaserLog(options);
}

}  // namespace calib::cli
