#include <calib/core/bearing/bearing_log_io.h>
#include <calib/solvers/common/robust_loss.h>
#include <calib/tools/report/bearing_diagnose_report.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/diagnosis_json.h>
#include <calib/tools/report/laser_diagnose_report.h>
#include <calib/tools/report/svg_plot.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace calib {

nlohmann::ordered_json BearingDiagnosisJson(const BearingDiagnosis& diagnosis,
                                            const std::string& input,
                                            const std::vector<std::string>& plots) {
  nlohmann::ordered_json out = DiagnosisJson(ToDiagnosisReport(diagnosis), input, plots);
  out["noise"] = {{"bearing_sigma_rad", diagnosis.base.noise.bearing_sigma_rad},
                  {"encoder_k", diagnosis.base.noise.encoder_k}};
  return out;
}

std::string BearingDiagnosisSummary(const BearingDiagnosis& diagnosis, const std::string& input,
                                    const std::vector<std::string>& plots) {
  const DiagnosisReport report = ToDiagnosisReport(diagnosis);
  char line[512];
  std::snprintf(line, sizeof(line), "%s: bearing-only diagnosis, %d bearings\n", input.c_str(),
                diagnosis.samples);
  std::string text = line + FindingsSummary(report);
  std::vector<ParamDisplay> params;
  for (int i = 0; i < kNumBearingParams; ++i) {
    const ParamInfo& info = BearingParamTable()[i];
    params.push_back({std::string(info.name) + (info.is_angle ? " [deg]" : ""),
                      info.is_angle ? info.display_scale : 1.0});
  }
  text += ParameterShiftTable(params, ToVector(diagnosis.baseline.estimate),
                              diagnosis.baseline.stddev, ToVector(diagnosis.final_fit.estimate),
                              diagnosis.final_fit.stddev, 12, 5);
  std::snprintf(line, sizeof(line), "  bearing RMS of the inliers: before %.4f°, after %.4f°\n",
                diagnosis.baseline.rms_rad * 180.0 / M_PI,
                diagnosis.final_fit.rms_rad * 180.0 / M_PI);
  return text + line + ResidualsSummary(report, plots);
}

StatusOr<std::vector<std::string>> WriteBearingDiagnosisPlots(const BearingDiagnosis& diagnosis,
                                                              const std::string& directory) {
  return WritePlotFiles(directory,
                        DiagnosisPlots(ToDiagnosisReport(diagnosis), "bearing residuals"));
}

}  // namespace calib
