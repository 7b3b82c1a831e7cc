#include <calib/core/laser/laser_log_io.h>
#include <calib/tools/report/bearing_diagnose_report.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/laser_diagnose_report.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace calib {
namespace {

namespace fs = std::filesystem;


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


}  // namespace calib
