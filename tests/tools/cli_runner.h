#ifndef CALIB_TESTS_TOOLS_CLI_RUNNER_H_
#define CALIB_TESTS_TOOLS_CLI_RUNNER_H_

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

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

// `scratch` receives the captured stdout.txt and stderr.txt.
inline CliRun RunCalib(const std::string& args, const std::filesystem::path& scratch) {
  const std::filesystem::path out = scratch / "stdout.txt", err = scratch / "stderr.txt";
  const std::string command = std::string(CALIB_BINARY_DIR) + "/bin/calib " + args + " >" +
                              out.string() + " 2>" + err.string() + " </dev/null";
  const int status = std::system(command.c_str());
  CliRun run;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = ReadFile(out);
  run.err = ReadFile(err);
  return run;
}

}  // namespace calib::testing

#endif  // CALIB_TESTS_TOOLS_CLI_RUNNER_H_
