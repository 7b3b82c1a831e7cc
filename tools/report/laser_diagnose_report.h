#ifndef CALIB_TOOLS_REPORT_LASER_DIAGNOSE_REPORT_H_
#define CALIB_TOOLS_REPORT_LASER_DIAGNOSE_REPORT_H_

#include <calib/solvers/laser/laser_diagnosis.h>
#include <calib/tools/report/diagnosis_json.h>
#include <calib/tools/report/svg_plot.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// `calib diagnose`: the contract's OUT.json, the before/after residual plots (SVG) and the
// human summary for a laser diagnosis.
namespace calib {

// The contract's {"baseline", "findings", "final"} plus the evidence behind each finding:
// DiagnosisJson(ToDiagnosisReport(diagnosis), input, plots) (tools/report/diagnosis_json.h).
// `plots` are the files written (relative or absolute, as given).
nlohmann::ordered_json LaserDiagnosisJson(const LaserDiagnosis& diagnosis, const std::string& input,
                                          const std::vector<std::string>& plots);

// The short summary printed on stdout (mm, degrees, ms).
std::string LaserDiagnosisSummary(const LaserDiagnosis& diagnosis, const std::string& input,
                                  const std::vector<std::string>& plots);

// One SVG per adopted finding (residuals against its covariate, before and after) and one of the
// residuals against time; returns the files written, or an error naming the one that failed.
StatusOr<std::vector<std::string>> WriteLaserDiagnosisPlots(const LaserDiagnosis& diagnosis,
                                                            const std::string& directory);

// The plots of any diagnosis: each adopted finding's profile ("<effect>_vs_<covariate>.svg",
// titled "<effect>: <residuals> against <covariate>") and the residual profiles worth drawing:
// against time and against the covariates that the residual structure before or after names
// ("residuals_vs_<covariate>.svg").
PlotFiles DiagnosisPlots(const DiagnosisReport& report, const std::string& residuals);

// The summary's lines shared by both problems: the findings with their tags, the residual
// structure before and after, the notes and the plots.
std::string FindingsSummary(const DiagnosisReport& report);
std::string ResidualsSummary(const DiagnosisReport& report, const std::vector<std::string>& plots);

// The base parameters before and after the adopted effects, in display units (value × scale_i):
// a header and one row per parameter with baseline ± σ, final ± σ and the shift in baseline σ.
struct ParamDisplay {
  std::string name;  // With its unit, e.g. "r_l [mm]".
  double scale = 1.0;
};
std::string ParameterShiftTable(const std::vector<ParamDisplay>& params,
                                const Eigen::VectorXd& before, const Eigen::VectorXd& before_sigma,
                                const Eigen::VectorXd& after, const Eigen::VectorXd& after_sigma,
                                int name_width, int precision);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_LASER_DIAGNOSE_REPORT_H_
