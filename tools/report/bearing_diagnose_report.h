#ifndef CALIB_TOOLS_REPORT_BEARING_DIAGNOSE_REPORT_H_
#define CALIB_TOOLS_REPORT_BEARING_DIAGNOSE_REPORT_H_

#include <calib/core/status.h>
#include <calib/solvers/bearing/bearing_diagnosis.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// `calib diagnose` on a bearing log directory: the contract's OUT.json, the plots and the
// summary.
namespace calib {

nlohmann::ordered_json BearingDiagnosisJson(const BearingDiagnosis& diagnosis,
                                            const std::string& input,
                                            const std::vector<std::string>& plots);

std::string BearingDiagnosisSummary(const BearingDiagnosis& diagnosis, const std::string& input,
                                    const std::vector<std::string>& plots);

// The adopted finding's residuals against its covariate, before and after, and the residuals
// against time; returns the files written.
StatusOr<std::vector<std::string>> WriteBearingDiagnosisPlots(const BearingDiagnosis& diagnosis,
                                                              const std::string& directory);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_BEARING_DIAGNOSE_REPORT_H_
