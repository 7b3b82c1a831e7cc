#include <calib/core/laser/laser_log_io.h>
#include <calib/core/text_format.h>
#include <calib/tools/report/bearing_diagnose_report.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/laser_diagnose_report.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

namespace calib {

PlotFiles DiagnosisPlots(const DiagnosisReport& report, const std::string& residuals) {
  std::string what = residuals;
  if (!what.empty()) what[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(what[0])));
  PlotFiles files;
  for (const ReportedFinding& reported : report.findings) {
    const Finding& f = reported.finding;
    if (!f.significant) continue;
    files.emplace_back(
        FindingPlotName(f),
        CovariateProfileSvg(f.profile, EffectInWords(f.name) + ": " + residuals + " against " +
                                           CovariateInWords(f.location.covariate)));
  }
  for (const CovariateProfile& profile : report.covariates) {
    if (profile.name != "time" && profile.name != report.structure_before.covariate &&
        profile.name != report.structure_after.covariate) {
      continue;
    }
    files.emplace_back(
        "residuals_vs_" + profile.name + ".svg",
        CovariateProfileSvg(profile, what + " against " + CovariateInWords(profile.name)));
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
        f.significant
            ? "found"
            : (f.implausible
                   ? "structure"
                   : (f.confounded ? "confounded" : (f.no_information ? "unseen" : "not found")));
    text += "  [" + std::string(tag) + "] " + f.statement + "\n";
  }
  return text;
}

std::string ParameterShiftTable(const std::vector<ParamDisplay>& params,
                                const Eigen::VectorXd& before, const Eigen::VectorXd& before_sigma,
                                const Eigen::VectorXd& after, const Eigen::VectorXd& after_sigma,
                                int name_width, int precision) {
  const int w = name_width, p = precision;
  std::string text = Format("  %-*s %12s %10s %12s %10s %8s\n", w, "parameter", "baseline", "± σ",
                            "final", "± σ", "shift/σ");
  for (size_t i = 0; i < params.size(); ++i) {
    const double k = params[i].scale, sigma = before_sigma(i);
    text += Format("  %-*s %12.*f %10.*f %12.*f %10.*f %8.2f\n", w, params[i].name.c_str(), p,
                   before(i) * k, p, sigma * k, p, after(i) * k, p, after_sigma(i) * k,
                   sigma > 0.0 ? (after(i) - before(i)) / sigma : 0.0);
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
  std::vector<ParamDisplay> params;
  for (const ParamInfo& info : kLaserParams) {
    params.push_back({std::string(info.name) + " [" + info.display_unit + "]", info.display_scale});
  }
  text += ParameterShiftTable(params, diagnosis.baseline.estimate.ToVector(),
                              diagnosis.baseline.stddev, diagnosis.final_fit.estimate.ToVector(),
                              diagnosis.final_fit.stddev, 14, 4);
  std::snprintf(line, sizeof(line),
                "  residual RMS of the inliers (x mm, y mm, θ mrad): before %.3f %.3f %.3f, after "
                "%.3f %.3f %.3f\n",
                diagnosis.baseline.rms(0) * 1e3, diagnosis.baseline.rms(1) * 1e3,
                diagnosis.baseline.rms(2) * 1e3, diagnosis.final_fit.rms(0) * 1e3,
                diagnosis.final_fit.rms(1) * 1e3, diagnosis.final_fit.rms(2) * 1e3);
  return text + line + ResidualsSummary(report, plots);
}

}  // namespace calib
