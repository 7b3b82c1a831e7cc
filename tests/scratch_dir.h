#ifndef CALIB_TESTS_SCRATCH_DIR_H_
#define CALIB_TESTS_SCRATCH_DIR_H_

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <system_error>

namespace calib::testing {

// A fresh folder in the temporary directory, named `prefix`, the process id and the running
// test's name: ctest runs each test in its own process, several at once, so a folder shared by
// name would be removed under another test's feet. The caller removes it.
inline std::filesystem::path MakeScratchDir(const std::string& prefix) {
  // Outside a test (a suite's set-up) there is no running test: the suite's name instead.
  const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
  const ::testing::TestSuite* suite = ::testing::UnitTest::GetInstance()->current_test_suite();
  std::string name = test != nullptr ? test->name() : suite != nullptr ? suite->name() : "setup";
  std::replace(name.begin(), name.end(), '/', '_');  // Parameterized names hold slashes.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()) + "_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// MakeScratchDir's folder, removed with this object.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& prefix) : path_(MakeScratchDir(prefix)) {}
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace calib::testing

#endif  // CALIB_TESTS_SCRATCH_DIR_H_
