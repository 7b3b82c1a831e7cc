#ifndef CALIB_TOOLS_REPORT_DIAGNOSIS_JSON_H_
#define CALIB_TOOLS_REPORT_DIAGNOSIS_JSON_H_

#include <calib/solvers/diagnosis/finding.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// The JSON of `calib diagnose` (OUT.json) for any problem, from the problem-independent
// DiagnosisReport (ToDiagnosisReport of a LaserDiagnosis or a BearingDiagnosis). One schema for
// both problems; data/diagnose/README.md documents it. Flag-free, usable from C++:
//   nlohmann::ordered_json j = DiagnosisJson(ToDiagnosisReport(*DiagnoseLaser(log)), path, {});
namespace calib {

// {"problem", "input", "samples", "units", "baseline", "findings", "final",
//  "residual_structure", "figures", "notes", "steps", "seconds"}. `plots`: the SVG files written
// (named in the findings whose plot they are).
nlohmann::ordered_json DiagnosisJson(const DiagnosisReport& report, const std::string& input,
                                     const std::vector<std::string>& plots);

// The parts, for reports that embed them.
nlohmann::ordered_json FitReportJson(const FitReport& fit);
nlohmann::ordered_json FindingJson(const ReportedFinding& finding, const ParamTable& params,
                                   const std::vector<std::string>& plots);
nlohmann::ordered_json ProfileJson(const CovariateProfile& profile);
nlohmann::ordered_json StructureJson(const ResidualStructure& structure);

// "<effect>_vs_<covariate>.svg": the file name of an adopted finding's plot.
std::string FindingPlotName(const Finding& finding);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_DIAGNOSIS_JSON_H_
