#ifndef CALIB_TESTS_TOOLS_CLI_RUNNER_H_
#define CALIB_TESTS_TOOLS_CLI_RUNNER_H_

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "tests/scratch_dir.h"

// Runs build/bin/calib as a user would (no standard input) and captures what it says.
namespace calib::testing {

struct CliRun {
  int exit_code = -1;  // -1 when the process did not exit normally (a crash).
  std::string out;
  std::string err;
};

inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// `scratch` receives the captured stdout.txt and stderr.txt; `working_dir`: where it runs (empty:
// here).
inline CliRun RunCalib(const std::string& args, const std::filesystem::path& scratch,
                       const std::filesystem::path& working_dir = {}) {
  const std::filesystem::path out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string cd = working_dir.empty() ? "" : "cd " + working_dir.string() + " && ";
  const std::string command = cd + std::string(CALIB_BINARY_DIR) + "/bin/calib " + args + " >" +
                              out.string() + " 2>" + err.string() + " </dev/null";
  const int status = std::system(command.c_str());
  CliRun run;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = ReadFile(out);
  run.err = ReadFile(err);
  return run;
}

// `source` (a CSV with a header) rewritten into `target` with `edit` applied to every row's
// numbers, in order.
using CsvRowEdit =
    std::function<void(const std::vector<std::string>& header, std::vector<double>* row)>;
inline void RewriteCsv(const std::filesystem::path& source, const std::filesystem::path& target,
                       const CsvRowEdit& edit) {
  std::istringstream in(ReadFile(source));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  std::stringstream names(line);
  for (std::string name; std::getline(names, name, ',');) header.push_back(name);
  std::ostringstream out;
  out.precision(17);
  out << line << "\n";
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
    edit(header, &row);
    for (size_t i = 0; i < row.size(); ++i) out << (i ? "," : "") << row[i];
    out << "\n";
  }
  std::ofstream(target) << out.str();
}

inline size_t CsvColumn(const std::vector<std::string>& header, const std::string& name) {
  for (size_t i = 0; i < header.size(); ++i) {
    if (header[i] == name) return i;
  }
  ADD_FAILURE() << "no column " << name;
  return 0;
}

}  // namespace calib::testing

#endif  // CALIB_TESTS_TOOLS_CLI_RUNNER_H_
