#ifndef CALIB_TOOLS_REPORT_LASER_DIAGNOSE_REPORT_H_
#define CALIB_TOOLS_REPORT_LASER_DIAGNOSE_REPORT_H_

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include <calib/solvers/laser/laser_diagnosis.h>

// `calib diagnose`: the contract's OUT.json, the before/after residual plots (SVG) and the
// human summary for a laser diagnosis.
namespace calib {

// The contract's {"baseline", "findings", "final"} plus the evidence behind each finding.
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

// The JSON of a covariate profile and of a residual structure (shared by both problems).
nlohmann::ordered_json ProfileJson(const CovariateProfile& profile);
nlohmann::ordered_json StructureJson(const ResidualStructure& structure);

// SVG files to write, (file name, content), and the writer (creates the folder; returns the
// paths written, or an error naming the file that failed).
using PlotFiles = std::vector<std::pair<std::string, std::string>>;
StatusOr<std::vector<std::string>> WritePlotFiles(const std::string& directory,
                                                  const PlotFiles& files);
// Adds the residual profiles worth drawing: against time and against the covariates that the
// residual structure before or after names ("residuals_vs_<covariate>.svg").
void AddResidualPlots(const std::vector<CovariateProfile>& covariates,
                      const ResidualStructure& before, const ResidualStructure& after,
                      const std::string& title, PlotFiles* files);

// The SVG of one covariate profile (exposed for tests).
std::string CovariateProfileSvg(const CovariateProfile& profile, const std::string& title);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_LASER_DIAGNOSE_REPORT_H_
