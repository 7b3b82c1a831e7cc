// Change points of a series over time (solvers/stats/change_point.h).
#include <calib/solvers/stats/change_point.h>
#include <gtest/gtest.h>

#include <random>

namespace calib {
namespace {

TEST(ChangePointTest, CusumFindsAMeanShiftAndNotNoise) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd series(1000, 1);
  for (int k = 0; k < 1000; ++k) series(k, 0) = normal(rng) + (k >= 640 ? 0.4 : 0.0);
  const std::vector<SeriesSegment> segments = SegmentMeans(series, 0.01, 3, 0.05, 20);
  ASSERT_GE(segments.size(), 2u);
  EXPECT_NEAR(static_cast<double>(segments[1].begin), 640.0, 30.0);
  for (int k = 0; k < 1000; ++k) series(k, 0) = normal(rng);
  EXPECT_EQ(SegmentMeans(series, 0.01, 3, 0.05, 20).size(), 1u);
}

}  // namespace
}  // namespace calib
