// The published recordings of Censi et al. (../shared/data/censi2013): our calibration against
// the authors' published results, and the three disjoint subsets of each set against each other.
#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace calib {
namespace {

namespace fs = std::filesystem;

const fs::path kDataDir = CALIB_CENSI_DATA_DIR;

// Reads a number after "key": in the published results file (a flat JSON object).
double ReadNumber(const std::string& text, const std::string& key) {
  const size_t at = text.find("\"" + key + "\"");
  EXPECT_NE(at, std::string::npos) << key;
  return std::stod(text.substr(text.find(':', at) + 1));
}

LaserParamVector Published(const std::string& set) {
  std::ifstream in(kDataDir / (set + "_results.json"));
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  LaserParamVector v;
  // The published file holds wheel diameters.
  v << ReadNumber(text, "l_diam") / 2, ReadNumber(text, "r_diam") / 2, ReadNumber(text, "axle"),
      ReadNumber(text, "l_x"), ReadNumber(text, "l_y"), ReadNumber(text, "l_theta");
  return v;
}

LaserCalibrationResult Calibrate(const std::string& file) {
  const StatusOr<LaserLog> log = ReadLaserLog((kDataDir / file).string());
  EXPECT_TRUE(log.ok()) << log.message();
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log->intervals);
  EXPECT_TRUE(result.ok()) << result.message();
  return *result;
}

class CensiDataTest : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (!fs::exists(kDataDir / "l90.tuple")) {
      GTEST_SKIP() << "the published recordings are not at " << kDataDir
                   << " (they are not part of the repository)";
    }
  }
};

TEST_P(CensiDataTest, AgreesWithThePublishedResult) {
  const LaserCalibrationResult result = Calibrate(GetParam() + ".tuple");
  const LaserParamVector diff = result.estimate.ToVector() - Published(GetParam());
  // The tolerances: about one published sigma.
  EXPECT_LE(std::abs(diff(0)), 0.1e-3);
  EXPECT_LE(std::abs(diff(1)), 0.1e-3);
  EXPECT_LE(std::abs(diff(2)), 0.4e-3);
  EXPECT_LE(std::abs(diff(3)), 0.4e-3);
  EXPECT_LE(std::abs(diff(4)), 0.4e-3);
  EXPECT_LE(std::abs(diff(5)), 0.3 * M_PI / 180);
  EXPECT_GT(result.inliers, 0.9 * result.samples);
}

TEST_P(CensiDataTest, DisjointSubsetsAgreeWithinThreeSigmas) {
  std::vector<LaserCalibrationResult> subsets;
  for (int k = 0; k < 3; ++k)
    subsets.push_back(Calibrate(GetParam() + "_" + std::to_string(k) + ".tuple"));
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      for (int i = 0; i < kNumLaserParams; ++i) {
        const double diff = subsets[a].estimate.ToVector()(i) - subsets[b].estimate.ToVector()(i);
        const double sigma = std::hypot(subsets[a].stddev(i), subsets[b].stddev(i));
        EXPECT_LT(std::abs(diff), 3 * sigma)
            << GetParam() << " subsets " << a << ", " << b << ": " << kLaserParamNames[i];
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Sets, CensiDataTest, ::testing::Values("l90", "lmov", "lstraight"));

}  // namespace
}  // namespace calib
