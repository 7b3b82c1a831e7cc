// The consistency object of the laser JSON and its summary lines, from a result built by hand.
#include <calib/tools/report/consistency_report.h>
#include <calib/tools/report/laser_report.h>
#include <gtest/gtest.h>

#include <cmath>

namespace calib {
namespace {

LaserConsistency Disagreeing() {
  LaserConsistency c;
  c.checked = true;
  c.tests = 2;
  LaserConsistencyWindow w;
  w.kind = "run";
  w.first = 0;
  w.last = 276;
  w.intervals = 270;
  w.end_s = 180.0;
  w.rotation.predicted = 554.0 * M_PI / 180.0;
  w.rotation.measured = 657.0 * M_PI / 180.0;
  w.rotation.sigma = 6.0 * M_PI / 180.0;
  w.rotation.z = 103.0 / 6.0;
  w.rotation.significant = true;
  c.windows.push_back(w);
  c.warnings.push_back("the wheel model predicts 554.0° ± 6.0° of rotation");
  return c;
}

TEST(ConsistencyReportTest, JsonListsEveryWindow) {
  const nlohmann::ordered_json json = LaserConsistencyJson(Disagreeing());
  EXPECT_EQ(json["checked"], true);
  ASSERT_EQ(json["windows"].size(), 1u);
  const auto& w = json["windows"][0];
  EXPECT_EQ(w["kind"], "run");
  EXPECT_EQ(w["first_interval"], 1);
  EXPECT_EQ(w["last_interval"], 277);
  EXPECT_NEAR(w["rotation_rad"]["measured"].get<double>(), 657.0 * M_PI / 180.0, 1e-12);
  EXPECT_NEAR(w["rotation_rad"]["difference"].get<double>(), 103.0 * M_PI / 180.0, 1e-12);
  EXPECT_EQ(w["rotation_rad"]["significant"], true);
  EXPECT_EQ(w["translation_m"]["significant"], false);
  EXPECT_EQ(json["warnings"].size(), 1u);
}

TEST(ConsistencyReportTest, LaserReportCarriesTheCheck) {
  LaserCalibrationResult result;
  result.consistency = Disagreeing();
  const nlohmann::ordered_json json = LaserResultJson(result, "sim", "cauchy");
  EXPECT_EQ(json["consistency"]["windows"][0]["rotation_rad"]["significant"], true);
  const std::string text = LaserResultSummary(result, "sim", "cauchy");
  EXPECT_NE(text.find("rotation 554.0° predicted, 657.0° measured"), std::string::npos) << text;
  EXPECT_NE(text.find("1 of 1 windows disagree"), std::string::npos) << text;
}

TEST(ConsistencyReportTest, UncheckedSaysWhy) {
  LaserConsistency c;
  c.note = "not checked: the calibration has no covariance";
  EXPECT_EQ(LaserConsistencyJson(c)["checked"], false);
  EXPECT_NE(LaserConsistencySummary(c).find("no covariance"), std::string::npos);
}

}  // namespace
}  // namespace calib
