#include <calib/tools/report/json_output.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>

namespace calib {
namespace {

// "cannot write PATH: why" (errno, when the system said why).
Status CannotWrite(const std::string& path, int error) {
  return Status::Io("cannot write " + path +
                    (error != 0 ? ": " + std::string(std::strerror(error)) : ""));
}

}  // namespace

Status WriteTextFile(const std::string& path, const std::string& text) {
  errno = 0;
  std::ofstream out(path);
  if (!out) return CannotWrite(path, errno);
  out << text;
  out.close();
  if (!out) {
    const int error = errno;
    // A report cut short (a full disk) is removed, not left to be read as complete.
    std::error_code ignored;
    if (std::filesystem::is_regular_file(path, ignored)) std::filesystem::remove(path, ignored);
    return CannotWrite(path, error);
  }
  return Status::Ok();
}

Status WriteJsonFile(const std::string& path, const nlohmann::ordered_json& json, int indent) {
  return WriteTextFile(path, json.dump(indent) + "\n");
}

Status WriteJsonFile(const std::string& path, const nlohmann::json& json, int indent) {
  return WriteTextFile(path, json.dump(indent) + "\n");
}

nlohmann::ordered_json ReportHeader(const std::string& problem, const std::string& input,
                                    const std::string& units) {
  nlohmann::ordered_json json;
  json["problem"] = problem;
  json["input"] = input;
  json["units"] = units;
  return json;
}

nlohmann::ordered_json MatrixJson(const Eigen::MatrixXd& matrix) {
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (int i = 0; i < matrix.rows(); ++i) {
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (int j = 0; j < matrix.cols(); ++j) row.push_back(matrix(i, j));
    rows.push_back(row);
  }
  return rows;
}

}  // namespace calib
