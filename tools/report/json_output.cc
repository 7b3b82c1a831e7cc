#include <calib/tools/report/json_output.h>

#include <fstream>

namespace calib {

Status WriteTextFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) return Status::Io("cannot write " + path);
  out << text;
  out.close();
  if (!out) return Status::Io("cannot write " + path);
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
