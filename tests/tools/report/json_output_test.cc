// The one JSON file writer: the layout of every file calib writes, and its errors.
#include <calib/tools/report/json_output.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tests/scratch_dir.h"

namespace calib {
namespace {

namespace fs = std::filesystem;

std::string Slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class JsonOutputTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeScratchDir("json_output_test_"); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(JsonOutputTest, WritesTheDumpAndANewline) {
  nlohmann::ordered_json json;
  json["b"] = 1;
  json["a"] = {1.5, 2};
  const fs::path path = dir_ / "out.json";
  ASSERT_TRUE(WriteJsonFile(path.string(), json).ok());
  EXPECT_EQ(Slurp(path), json.dump(2) + "\n");
  // Keys keep their insertion order.
  EXPECT_LT(Slurp(path).find("\"b\""), Slurp(path).find("\"a\""));

  const nlohmann::json unordered = {{"mode", "quick"}, {"threads", 2}};
  ASSERT_TRUE(WriteJsonFile(path.string(), unordered, 1).ok());
  EXPECT_EQ(Slurp(path), unordered.dump(1) + "\n");
}

TEST_F(JsonOutputTest, AnUnwritablePathIsAnIoErrorNamingIt) {
  const std::string path = (dir_ / "missing_folder" / "out.json").string();
  const Status status = WriteJsonFile(path, nlohmann::ordered_json::object());
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), StatusCode::kIo);
  EXPECT_EQ(status.message(), "cannot write " + path + ": No such file or directory");
  EXPECT_EQ(WriteTextFile(path, "x").code(), StatusCode::kIo);
}

TEST_F(JsonOutputTest, AFullDiskIsAnIoErrorSayingSo) {
  const Status status = WriteTextFile("/dev/full", std::string(1 << 16, 'x'));
  EXPECT_EQ(status.code(), StatusCode::kIo);
  EXPECT_EQ(status.message(), "cannot write /dev/full: No space left on device");
}

TEST_F(JsonOutputTest, AFileCutShortIsRemoved) {
  // A file size limit makes the write fail part way, as a full disk does (EFBIG, not SIGXFSZ).
  const fs::path path = dir_ / "report.json";
  std::signal(SIGXFSZ, SIG_IGN);
  rlimit old_limit{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  rlimit small = old_limit;
  small.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  const Status status = WriteTextFile(path.string(), std::string(1 << 16, 'x'));
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &old_limit), 0);
  EXPECT_EQ(status.code(), StatusCode::kIo);
  EXPECT_EQ(status.message().rfind("cannot write " + path.string() + ": ", 0), 0u)
      << status.message();
  EXPECT_FALSE(fs::exists(path));
}

TEST_F(JsonOutputTest, MatrixIsAnArrayOfRows) {
  Eigen::MatrixXd m(2, 3);
  m << 1, 2, 3, 4, 5, 6;
  EXPECT_EQ(MatrixJson(m).dump(), "[[1.0,2.0,3.0],[4.0,5.0,6.0]]");
  EXPECT_EQ(MatrixJson(Eigen::MatrixXd(0, 0)).dump(), "[]");
}

TEST_F(JsonOutputTest, ReportHeaderComesFirst) {
  nlohmann::ordered_json json = ReportHeader("laser", "a.tuple", "m, rad");
  json["estimate"] = 1;
  EXPECT_EQ(json.dump(), R"({"problem":"laser","input":"a.tuple","units":"m, rad","estimate":1})");
}

}  // namespace
}  // namespace calib
