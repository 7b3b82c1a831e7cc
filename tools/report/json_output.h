#ifndef CALIB_TOOLS_REPORT_JSON_OUTPUT_H_
#define CALIB_TOOLS_REPORT_JSON_OUTPUT_H_

#include <calib/core/status.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>

// The one place where calib writes its files (the tool's reports, calib_bench's results) and the
// JSON pieces its reports share.
namespace calib {

// Writes `text` to `path`, replacing the file; Status::Io "cannot write PATH: why" when it cannot
// (a regular file cut short by a failed write is removed).
Status WriteTextFile(const std::string& path, const std::string& text);

// Writes json.dump(indent) and a newline: the layout of every JSON file calib writes (indent 2
// for the tool's reports, 1 for calib_bench's results).
Status WriteJsonFile(const std::string& path, const nlohmann::ordered_json& json, int indent = 2);
Status WriteJsonFile(const std::string& path, const nlohmann::json& json, int indent = 2);

// The members every report starts with: {"problem", "input", "units"}.
nlohmann::ordered_json ReportHeader(const std::string& problem, const std::string& input,
                                    const std::string& units);

// A matrix as an array of rows.
nlohmann::ordered_json MatrixJson(const Eigen::MatrixXd& matrix);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_JSON_OUTPUT_H_
