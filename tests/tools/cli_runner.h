#ifndef CALIB_TESTS_TOOLS_CLI_RUNNER_H_
#define CALIB_TESTS_TOOLS_CLI_RUNNER_H_

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

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

// A fresh folder in the temporary directory, named `prefix`, the process id and the running
// test's name (so that concurrent runs do not meet); the caller removes it.
inline std::filesystem::path MakeScratchDir(const std::string& prefix) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      (prefix + std::to_string(::getpid()) + "_" +
       ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
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

}  // namespace calib::testing

#endif  // CALIB_TESTS_TOOLS_CLI_RUNNER_H_
