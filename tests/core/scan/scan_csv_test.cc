#include <calib/core/scan/scan_csv.h>
#include <calib/core/scan/scan_simulator.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

namespace calib {
namespace {

std::vector<LaserScan> SimulatedScans() {
  ScanSimOptions options;
  options.laser.num_intervals = 4;
  options.beams = 181;
  options.field_of_view_rad = M_PI;
  options.sweep_s = 0.05;
  options.range_noise_sigma_m = 0.01;
  options.missing_probability = 0.1;
  options.range_max_m = 8.0;
  std::vector<LaserScan> scans = SimulateScans(options)->scans;
  scans[1].ranges_m[3] = std::numeric_limits<float>::quiet_NaN();
  scans[2].ranges_m[5] = -std::numeric_limits<float>::infinity();
  return scans;
}

bool SameBits(float a, float b) {
  if (std::isnan(a)) return std::isnan(b);
  return std::memcmp(&a, &b, sizeof(a)) == 0;
}

void ExpectSame(const std::vector<LaserScan>& a, const std::vector<LaserScan>& b,
                double increment_tolerance) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].stamp_s, b[k].stamp_s);
    EXPECT_EQ(a[k].angle_min_rad, b[k].angle_min_rad);
    EXPECT_NEAR(a[k].angle_increment_rad, b[k].angle_increment_rad, increment_tolerance);
    EXPECT_EQ(a[k].time_increment_s, b[k].time_increment_s);
    EXPECT_EQ(a[k].range_min_m, b[k].range_min_m);
    EXPECT_EQ(a[k].range_max_m, b[k].range_max_m);
    ASSERT_EQ(a[k].ranges_m.size(), b[k].ranges_m.size());
    for (size_t i = 0; i < a[k].ranges_m.size(); ++i) {
      EXPECT_TRUE(SameBits(a[k].ranges_m[i], b[k].ranges_m[i])) << k << " " << i;
    }
  }
}

TEST(ScanCsvTest, WideRoundTripIsExact) {
  const std::vector<LaserScan> scans = SimulatedScans();
  const StatusOr<std::vector<LaserScan>> back =
      ParseScanCsv(FormatScanCsv(scans, ScanCsvLayout::kWide), "scans.csv");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSame(scans, *back, 0.0);
  EXPECT_EQ((*back)[1].record, 3);  // The line: header, then one scan per line.
}

TEST(ScanCsvTest, LongRoundTripIsExactButForTheIncrementsLastBits) {
  const std::vector<LaserScan> scans = SimulatedScans();
  const std::string text = FormatScanCsv(scans, ScanCsvLayout::kLong);
  const StatusOr<std::vector<LaserScan>> back = ParseScanCsv(text, "scans.csv");
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSame(scans, *back, 1e-15);
  // Written again, the text is the same.
  EXPECT_EQ(FormatScanCsv(*back, ScanCsvLayout::kLong).size(), text.size());
}

TEST(ScanCsvTest, MinimalWideAndLongWithNoReturns) {
  const StatusOr<std::vector<LaserScan>> wide = ParseScanCsv(
      "# a comment\nt,angle_min,angle_increment,range_0,range_1,range_2\n"
      "1.5,-1,0.5,2.25,,NaN\n2,-1,0.5,inf,1,-INF\n",
      "w.csv");
  ASSERT_TRUE(wide.ok()) << wide.status().message();
  ASSERT_EQ(wide->size(), 2u);
  EXPECT_EQ((*wide)[0].ranges_m[0], 2.25f);
  EXPECT_TRUE(std::isnan((*wide)[0].ranges_m[1]));
  EXPECT_TRUE(std::isnan((*wide)[0].ranges_m[2]));
  EXPECT_TRUE(std::isinf((*wide)[1].ranges_m[0]));
  EXPECT_TRUE((*wide)[0].IsReturn(0));
  EXPECT_FALSE((*wide)[1].IsReturn(0));
  const StatusOr<std::vector<LaserScan>> long_scans =
      ParseScanCsv("t,angle,range\n1,0,1\n1,0.25,2\n1,0.5,\n2,-1,3\n", "l.csv");
  ASSERT_TRUE(long_scans.ok()) << long_scans.status().message();
  ASSERT_EQ(long_scans->size(), 2u);
  EXPECT_EQ((*long_scans)[0].ranges_m.size(), 3u);
  EXPECT_EQ((*long_scans)[0].angle_increment_rad, 0.25);
  EXPECT_EQ((*long_scans)[1].angle_min_rad, -1.0);
  EXPECT_EQ((*long_scans)[1].ranges_m.size(), 1u);
}

void ExpectError(const std::string& text, const std::vector<std::string>& words) {
  const StatusOr<std::vector<LaserScan>> result = ParseScanCsv(text, "bad.csv");
  ASSERT_FALSE(result.ok()) << text;
  for (const std::string& word : words) {
    EXPECT_NE(result.status().message().find(word), std::string::npos)
        << result.status().message() << " lacks " << word;
  }
}

TEST(ScanCsvTest, BadInputsNameFileLineAndProblem) {
  const std::string header = "t,angle_min,angle_increment,range_0,range_1\n";
  ExpectError(header + "1,0,0.1,1,2\n0.5,0,0.1,1,2\n", {"bad.csv:3", "does not increase"});
  ExpectError(header + "1,0,0.1,1,2\n1,0,0.1,1,3\n",
              {"bad.csv:3", "repeats the scan before (line 2)"});
  ExpectError(header + "1,0,0.1,1,2\n2,0,0.1,1\n", {"bad.csv:3", "fields"});
  ExpectError(header + "1,0,0.1,1,x2\n", {"bad.csv:2", "range_1", "not a number", "x2"});
  ExpectError(header + "1,abc,0.1,1,2\n", {"bad.csv:2", "angle_min"});
  ExpectError("t,angle_min,angle_increment,range_0,range_2\n1,0,0.1,1,2\n", {"bad.csv", "range_1"});
  ExpectError("t,angle_increment,range_0\n1,0.1,1\n", {"bad.csv", "angle_min"});
  ExpectError("t,angle_min,angle_increment\n1,0,0.1\n", {"bad.csv", "range_0"});
  ExpectError("t,angle\n1,0\n", {"bad.csv", "range"});
  ExpectError("t,angle,range\n2,0,1\n1,0,1\n", {"bad.csv:3", "does not increase"});
  ExpectError("t,angle,range\n1,0,1\n1,0.1,1\n1,0.3,1\n", {"bad.csv:3", "even grid"});
  ExpectError("t,angle,range\n1,0,1\n1,0.1,1\n1,0,1\n1,0.1,2\n", {"bad.csv:4", "repeats"});
  ExpectError("", {"bad.csv", "no header"});
}

// A scan written twice (every value repeated) is read as two scans, for LaserLogFromScans to
// drop with a warning; in the long layout its first angle again under the same t starts it.
TEST(ScanCsvTest, AScanWrittenTwiceIsReadTwice) {
  const std::string wide =
      "t,angle_min,angle_increment,range_0,range_1\n1,0,0.1,1,nan\n"
      "1,0,0.1,1,nan\n2,0,0.1,1.5,2\n";
  const std::string lines = "t,angle,range\n1,0,1\n1,0.1,\n1,0,1\n1,0.1,\n2,0,1.5\n2,0.1,2\n";
  for (const std::string& text : {wide, lines}) {
    const StatusOr<std::vector<LaserScan>> scans = ParseScanCsv(text, "twice.csv");
    ASSERT_TRUE(scans.ok()) << scans.message();
    ASSERT_EQ(scans->size(), 3u);
    EXPECT_EQ((*scans)[1].stamp_s, 1.0);
    ASSERT_EQ((*scans)[1].ranges_m.size(), 2u);
    EXPECT_TRUE(std::isnan((*scans)[1].ranges_m[1]));
    EXPECT_EQ((*scans)[2].ranges_m[1], 2.0f);
  }
}

TEST(ScanCsvTest, FileRoundTrip) {
  const std::vector<LaserScan> scans = SimulatedScans();
  const std::string path = std::string(CALIB_BINARY_DIR) + "/scan_csv_test_scans.csv";
  ASSERT_TRUE(WriteScanCsv(scans, ScanCsvLayout::kWide, path).ok());
  const StatusOr<std::vector<LaserScan>> back = ReadScanCsv(path);
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSame(scans, *back, 0.0);
  EXPECT_NE(ReadScanCsv(path + ".missing").status().message().find(".missing"), std::string::npos);
}

}  // namespace
}  // namespace calib
