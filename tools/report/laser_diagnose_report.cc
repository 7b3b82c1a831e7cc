#include <calib/core/laser/laser_log_io.h>
#include <calib/tools/report/bearing_diagnose_report.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/laser_diagnose_report.h>
#include <gflags/gflags.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

// Shared with `calib calibrate` (defined in calib_main.cc).
DECLARE_string(input);
DECLARE_string(output);
DECLARE_string(format);
DECLARE_string(loss);
DECLARE_double(loss_scale);
DECLARE_bool(quiet);

DEFINE_double(family_alpha, 0.01,
              "diagnose: family-wise error rate of each forward step (Holm over the candidates)");
DEFINE_int32(max_effects, 3, "diagnose: at most this many effects adopted");
DEFINE_int32(cv_blocks, 5, "diagnose: contiguous held-out blocks for the cross-validation");
DEFINE_string(candidates, "",
              "diagnose: comma-separated candidate effects (default all: time_offset, "
              "lateral_slip, longitudinal_slip, wheel_radius_change, speed_dependent_radius, "
              "icr_offset_x, scan_scale)");
DEFINE_string(boundary_speeds, "auto",
              "diagnose: wheel speeds at interval boundaries: auto, piecewise (constant within "
              "intervals) or smooth");
DEFINE_string(plots_dir, "",
              "diagnose: folder for the SVG plots (default: OUT_plots next to "
              "the JSON output)");

namespace calib {
namespace {

namespace fs = std::filesystem;

// The laser diagnosis' options from the flags (--loss, --loss_scale, --family_alpha,
// --max_effects, --cv_blocks, --boundary_speeds, --candidates).
StatusOr<LaserDiagnosisOptions> LaserOptionsFromFlags() {
  CALIB_ASSIGN_OR_RETURN(const RobustLoss loss, ParseRobustLoss(FLAGS_loss));
  if (!(FLAGS_loss_scale > 0.0)) return Status::InvalidInput("--loss_scale must be positive");
  if (FLAGS_max_effects < 0) return Status::InvalidInput("--max_effects must not be negative");
  LaserDiagnosisOptions options;
  options.calibration.refinement.loss = loss;
  options.calibration.refinement.loss_scale = FLAGS_loss_scale;
  options.alpha = FLAGS_family_alpha;
  options.max_effects = FLAGS_max_effects;
  options.cv_blocks = FLAGS_cv_blocks;
  if (FLAGS_boundary_speeds == "auto") {
    options.boundary = BoundaryChoice::kAuto;
  } else if (FLAGS_boundary_speeds == "piecewise") {
    options.boundary = BoundaryChoice::kPiecewiseConstant;
  } else if (FLAGS_boundary_speeds == "smooth") {
    options.boundary = BoundaryChoice::kSmooth;
  } else {
    return Status::InvalidInput("unknown --boundary_speeds '" + FLAGS_boundary_speeds +
                                "' (auto, piecewise or smooth)");
  }
  if (!FLAGS_candidates.empty()) {
    options.candidates.clear();
    std::stringstream stream(FLAGS_candidates);
    std::string name;
    while (std::getline(stream, name, ',')) {
      if (name.empty()) continue;
      CALIB_ASSIGN_OR_RETURN(const LaserEffect effect, ParseLaserEffect(name));
      options.candidates.push_back(effect);
    }
  }
  return options;
}

}  // namespace

PlotFiles DiagnosisPlots(const DiagnosisReport& report, const std::string& residuals) {
  PlotFiles files;
  for (const ReportedFinding& reported : report.findings) {
    const Finding& f = reported.finding;
    if (!f.significant) continue;
    files.emplace_back(FindingPlotName(f),
                       CovariateProfileSvg(f.profile, f.name + ": " + residuals + " against " +
                                                          f.location.covariate));
  }
  for (const CovariateProfile& profile : report.covariates) {
    if (profile.name != "time" && profile.name != report.structure_before.covariate &&
        profile.name != report.structure_after.covariate) {
      continue;
    }
    files.emplace_back("residuals_vs_" + profile.name + ".svg",
                       CovariateProfileSvg(profile, residuals + " against " + profile.name));
  }
  return files;
}

std::string FindingsSummary(const DiagnosisReport& report) {
  std::string adopted;
  for (const std::string& name : report.adopted) adopted += (adopted.empty() ? "" : ", ") + name;
  std::string text =
      "  adopted effects: " + (adopted.empty() ? std::string("none") : adopted) + "\n";
  for (const ReportedFinding& reported : report.findings) {
    const Finding& f = reported.finding;
    const char* tag =
        f.significant ? "found"
                      : (f.confounded ? "confounded" : (f.no_information ? "unseen" : "not found"));
    text += "  [" + std::string(tag) + "] " + f.statement + "\n";
  }
  return text;
}

std::string ResidualsSummary(const DiagnosisReport& report, const std::vector<std::string>& plots) {
  std::string text = "  residuals before: " + report.structure_before.statement + "\n";
  text += "  residuals after:  " + report.structure_after.statement + "\n";
  for (const std::string& note : report.notes) text += "  note: " + note + "\n";
  for (const std::string& plot : plots) text += "  plot: " + plot + "\n";
  return text;
}

StatusOr<std::vector<std::string>> WriteLaserDiagnosisPlots(const LaserDiagnosis& diagnosis,
                                                            const std::string& directory) {
  return WritePlotFiles(directory, DiagnosisPlots(ToDiagnosisReport(diagnosis), "residuals"));
}

nlohmann::ordered_json LaserDiagnosisJson(const LaserDiagnosis& diagnosis, const std::string& input,
                                          const std::vector<std::string>& plots) {
  return DiagnosisJson(ToDiagnosisReport(diagnosis), input, plots);
}

std::string LaserDiagnosisSummary(const LaserDiagnosis& diagnosis, const std::string& input,
                                  const std::vector<std::string>& plots) {
  const DiagnosisReport report = ToDiagnosisReport(diagnosis);
  char line[512];
  std::snprintf(line, sizeof(line), "%s: laser–odometry diagnosis, %d intervals\n", input.c_str(),
                diagnosis.samples);
  std::string text = line + FindingsSummary(report);
  std::snprintf(line, sizeof(line), "  %-14s %12s %10s %12s %10s %8s\n", "parameter", "baseline",
                "± σ", "final", "± σ", "shift/σ");
  text += line;
  const LaserParamVector before = diagnosis.baseline.estimate.ToVector();
  const LaserParamVector after = diagnosis.final_fit.estimate.ToVector();
  for (int i = 0; i < kNumLaserParams; ++i) {
    const ParamInfo& info = kLaserParams[i];
    const double k = info.display_scale;
    const std::string name = std::string(info.name) + " [" + info.display_unit + "]";
    const double sigma = diagnosis.baseline.stddev(i);
    std::snprintf(line, sizeof(line), "  %-14s %12.4f %10.4f %12.4f %10.4f %8.2f\n", name.c_str(),
                  before(i) * k, sigma * k, after(i) * k, diagnosis.final_fit.stddev(i) * k,
                  sigma > 0.0 ? (after(i) - before(i)) / sigma : 0.0);
    text += line;
  }
  std::snprintf(line, sizeof(line),
                "  residual RMS of the inliers (x mm, y mm, θ mrad): before %.3f %.3f %.3f, after "
                "%.3f %.3f %.3f\n",
                diagnosis.baseline.rms(0) * 1e3, diagnosis.baseline.rms(1) * 1e3,
                diagnosis.baseline.rms(2) * 1e3, diagnosis.final_fit.rms(0) * 1e3,
                diagnosis.final_fit.rms(1) * 1e3, diagnosis.final_fit.rms(2) * 1e3);
  return text + line + ResidualsSummary(report, plots);
}

int RunDiagnoseCommand() {
  const auto fail = [](const std::string& message) {
    std::fprintf(stderr, "calib: error: %s\n", message.c_str());
    return 1;
  };
  if (FLAGS_input.empty()) return fail("--input is required");
  if (FLAGS_output.empty()) return fail("--output is required");
  if (FLAGS_input.find(',') != std::string::npos) {
    return fail("diagnose takes one log (--input names several)");
  }
  if (!(FLAGS_family_alpha > 0.0 && FLAGS_family_alpha < 1.0)) {
    return fail("--family_alpha must be in (0, 1)");
  }
  if (FLAGS_cv_blocks < 2) return fail("--cv_blocks must be at least 2");
  if (FLAGS_format == "auto" && IsBearingLogDirectory(FLAGS_input)) {
    // One candidate (time_offset) for the bearing problem: --candidates, --max_effects and
    // --boundary_speeds concern the laser's.
    BearingDiagnoseFlags flags;
    flags.input = FLAGS_input;
    flags.output = FLAGS_output;
    flags.plots_dir = FLAGS_plots_dir;
    flags.loss = FLAGS_loss;
    flags.loss_scale = FLAGS_loss_scale;
    flags.alpha = FLAGS_family_alpha;
    flags.cv_blocks = FLAGS_cv_blocks;
    flags.quiet = FLAGS_quiet;
    return DiagnoseBearingCommand(flags);
  }
  const StatusOr<LaserFormat> format = ParseLaserFormat(FLAGS_format);
  if (!format.ok()) return fail(format.message());
  StatusOr<LaserDiagnosisOptions> parsed = LaserOptionsFromFlags();
  if (!parsed.ok()) return fail(parsed.message());
  LaserDiagnosisOptions options = *parsed;
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  options.progress = [&](const std::string& text) {
    if (elapsed() > 1.0 && !FLAGS_quiet) {
      std::fprintf(stderr, "calib: %.1f s: %s\n", elapsed(), text.c_str());
    }
  };

  const StatusOr<LaserLog> log = ReadLaserLog(FLAGS_input, *format);
  if (!log.ok()) return fail(log.message());
  const StatusOr<LaserDiagnosis> diagnosis = DiagnoseLaser(log->intervals, options);
  if (!diagnosis.ok()) return fail(FLAGS_input + ": " + diagnosis.message());

  std::string plots_dir = FLAGS_plots_dir;
  if (plots_dir.empty()) {
    fs::path output(FLAGS_output);
    plots_dir = (output.parent_path() / (output.stem().string() + "_plots")).string();
  }
  const StatusOr<std::vector<std::string>> plots = WriteLaserDiagnosisPlots(*diagnosis, plots_dir);
  if (!plots.ok()) return fail(plots.message());

  nlohmann::ordered_json json = LaserDiagnosisJson(*diagnosis, FLAGS_input, *plots);
  json["seconds"] = elapsed();
  std::ofstream out(FLAGS_output);
  if (!out) return fail("cannot write " + FLAGS_output);
  out << json.dump(2) << "\n";
  if (!out) return fail("cannot write " + FLAGS_output);
  if (!FLAGS_quiet) {
    std::fputs(LaserDiagnosisSummary(*diagnosis, FLAGS_input, *plots).c_str(), stdout);
  }
  return 0;
}

}  // namespace calib
