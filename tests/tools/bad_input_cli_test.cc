// The inputs of issue 14 through the real command line: each gets a clear error naming the file
// and record, or the answer the clean log gives; never a crash, a hang or a silent wrong number.
// One glitch (a wheel speed of 1000 rad/s, a T of 10⁴ s, π written as −π, a value of 1e300)
// costs its interval, not the answer.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/tools/cli_runner.h"

namespace {

namespace fs = std::filesystem;

using ::calib::testing::CliRun;
using ::calib::testing::CsvColumn;
using ::calib::testing::ReadFile;
using ::calib::testing::RewriteCsv;

const char* const kParams[] = {"r_l", "r_r", "b", "sensor_x", "sensor_y", "sensor_theta"};

class BadInputCliTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(::calib::testing::MakeScratchDir("bad_input_cli_test_"));
    for (const int n : {60, 1000}) {
      const CliRun run = Run("simulate --intervals " + std::to_string(n) + " --seed 11 --output " +
                             Clean(n).string());
      ASSERT_EQ(run.exit_code, 0) << run.err;
    }
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }

  static CliRun Run(const std::string& args) { return ::calib::testing::RunCalib(args, *dir_); }
  static fs::path Clean(int n) { return *dir_ / ("clean" + std::to_string(n) + ".csv"); }

  // The clean log of `n` intervals with `column` of record `record` (1-based) set to `value`;
  // `keep` rows only when positive.
  static fs::path Glitch(const std::string& name, int n, int record, const std::string& column,
                         double value, int keep = 0) {
    const fs::path path = *dir_ / (name + ".csv");
    int row_index = 0;
    RewriteCsv(Clean(n), path,
               [&](const std::vector<std::string>& header, std::vector<double>* row) {
                 if (++row_index == record && !column.empty())
                   (*row)[CsvColumn(header, column)] = value;
               });
    if (keep > 0) {
      std::ifstream in(path);
      std::string text, line;
      for (int i = 0; i <= keep && std::getline(in, line); ++i) text += line + "\n";
      std::ofstream(path) << text;
    }
    return path;
  }

  static nlohmann::json Calibrate(const fs::path& input, CliRun* run) {
    const fs::path out = input.string() + ".json";
    *run = Run("calibrate --input " + input.string() + " --output " + out.string());
    EXPECT_NE(run->exit_code, -1) << "crashed: " << run->err;
    if (run->exit_code != 0) return nlohmann::json();
    return nlohmann::json::parse(ReadFile(out));
  }

  // Every parameter within `sigmas` of the clean log's estimate, and the closed form sane.
  static void ExpectAsClean(const nlohmann::json& result, int n, double sigmas) {
    CliRun run;
    const nlohmann::json clean = Calibrate(Clean(n), &run);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    for (const char* p : kParams) {
      const double sigma = clean["stddev"][p].get<double>();
      EXPECT_NEAR(result["estimate"][p].get<double>(), clean["estimate"][p].get<double>(),
                  sigmas * sigma)
          << p;
      EXPECT_NEAR(result["closed_form"][p].get<double>(), clean["estimate"][p].get<double>(),
                  10 * sigma)
          << p << " (closed form)";
    }
  }

  static inline fs::path* dir_ = nullptr;
};

struct OneGlitch {
  const char* name;
  const char* column;
  double value;
  const char* warning;  // What the warnings say about it.
};

class OneGlitchTest : public BadInputCliTest, public ::testing::WithParamInterface<OneGlitch> {};

TEST_P(OneGlitchTest, CostsOneInterval) {
  const OneGlitch& glitch = GetParam();
  const fs::path input = Glitch(glitch.name, 1000, 501, glitch.column, glitch.value);
  CliRun run;
  const nlohmann::json result = Calibrate(input, &run);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ExpectAsClean(result, 1000, 0.5);
  const std::string warnings = result["warnings"].dump();
  EXPECT_EQ(warnings.find("wrong sign"), std::string::npos) << warnings;
  if (*glitch.warning != '\0') {
    EXPECT_NE(warnings.find(glitch.warning), std::string::npos) << warnings;
    EXPECT_NE(warnings.find("record 501"), std::string::npos) << warnings;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Issue14, OneGlitchTest,
    ::testing::Values(OneGlitch{"phi_l_1000", "phi_l", 1000.0, "left wheel's rotation"},
                      OneGlitch{"T_1e4", "T", 1e4, "T longer than the time to the next"},
                      OneGlitch{"sm_theta_1e300", "sm_theta", 1e300, "no unit explains"},
                      OneGlitch{"sm_theta_5e307", "sm_theta", 5e307, "no unit explains"},
                      OneGlitch{"sm_theta_minus_pi", "sm_theta", -M_PI, ""},
                      OneGlitch{"phi_r_minus_50", "phi_r", -50.0, ""},
                      OneGlitch{"sm_x_3m", "sm_x", 3.0, ""}),
    [](const ::testing::TestParamInfo<OneGlitch>& info) { return std::string(info.param.name); });

// T of 10⁴ s in a log without t: the interval's wheel rotation is then absurd.
TEST_F(BadInputCliTest, LongIntervalWithoutStamps) {
  const fs::path input = *dir_ / "no_t.csv";
  int index = 0;
  RewriteCsv(Clean(1000), input,
             [&](const std::vector<std::string>& header, std::vector<double>* row) {
               if (++index == 501) (*row)[CsvColumn(header, "T")] = 1e4;
             });
  // Without the t column (the first).
  std::ifstream in(input);
  std::string text, line;
  while (std::getline(in, line)) text += line.substr(line.find(',') + 1) + "\n";
  std::ofstream(input) << text;
  CliRun run;
  const nlohmann::json result = Calibrate(input, &run);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ExpectAsClean(result, 1000, 0.5);
}

// The fuzzer's crash: a finite but absurd value in logs of 3, 60 and 150 intervals.
TEST_F(BadInputCliTest, AbsurdValueInShortLogs) {
  CliRun run;
  Calibrate(Glitch("three_absurd", 60, 2, "sm_theta", 5e307, 3), &run);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("three_absurd.csv"), std::string::npos) << run.err;
  const nlohmann::json sixty = Calibrate(Glitch("sixty_absurd", 60, 2, "sm_theta", 5e307), &run);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ExpectAsClean(sixty, 60, 0.5);
}

// Three intervals cannot determine six unknowns with error bars: refused, saying why.
TEST_F(BadInputCliTest, TooFewIntervalsRefused) {
  CliRun run;
  Calibrate(Glitch("three", 60, 0, "", 0.0, 3), &run);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("three.csv"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("at least 24"), std::string::npos) << run.err;
  EXPECT_EQ(run.err.find("wrong sign"), std::string::npos) << run.err;
}

// θ in degrees: refused, not b = 0.28 mm with every interval an inlier.
TEST_F(BadInputCliTest, DegreesRefused) {
  const fs::path input = *dir_ / "degrees.csv";
  RewriteCsv(Clean(1000), input,
             [](const std::vector<std::string>& header, std::vector<double>* row) {
               (*row)[CsvColumn(header, "sm_theta")] *= 180.0 / M_PI;
             });
  CliRun run;
  Calibrate(input, &run);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("degrees"), std::string::npos) << run.err;
}

// 60 % of the scans matched wrongly: the robust loss cannot hold that; the verdict says so.
TEST_F(BadInputCliTest, MostlyOutliersIsUnreliable) {
  const fs::path input = *dir_ / "outliers60.csv";
  int index = 0;
  RewriteCsv(Clean(1000), input,
             [&](const std::vector<std::string>& header, std::vector<double>* row) {
               if (++index % 5 < 3) {
                 (*row)[CsvColumn(header, "sm_x")] += 0.3 * std::sin(index * 1.7);
                 (*row)[CsvColumn(header, "sm_y")] += 0.3 * std::cos(index * 2.3);
                 (*row)[CsvColumn(header, "sm_theta")] += 0.5 * std::sin(index * 0.9);
               }
             });
  CliRun run;
  const nlohmann::json result = Calibrate(input, &run);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(result["verdict"], "unreliable") << result["verdict_reason"];
  EXPECT_NEAR(result["gross_outlier_share"].get<double>(), 0.6, 0.05);
  EXPECT_NE(result["verdict_reason"].get<std::string>().find("disagree grossly"), std::string::npos)
      << result["verdict_reason"];
}

}  // namespace
