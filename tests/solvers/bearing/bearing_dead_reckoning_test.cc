#include <calib/core/bearing/bearing_log_io.h>
#include <calib/solvers/bearing/bearing_dead_reckoning.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

namespace calib {
namespace {

// The shipped sample: three runs whose wheels differ from meta.json's nominal ones (δR, δL, δB
// away from 1), with an initial distance (metres).
TEST(BearingDeadReckoningTest, CalibratedWheelsFollowTheAdjustedPathBetterThanNominal) {
  const StatusOr<BearingLog> log = ReadBearingLog(
      (std::filesystem::path(CALIB_SOURCE_DIR) / "data" / "sample_bearing").string());
  ASSERT_TRUE(log.ok()) << log.message();
  const StatusOr<BearingCalibrationResult> result = CalibrateBearing(*log);
  ASSERT_TRUE(result.ok()) << result.message();

  int inliers = 0;
  for (const auto& run : result->is_inlier) {
    inliers += static_cast<int>(std::count(run.begin(), run.end(), true));
  }
  EXPECT_EQ(inliers, result->inliers);

  const BearingPaths paths = BearingDeadReckoning(*log, *result);
  EXPECT_TRUE(paths.metric);
  ASSERT_EQ(paths.runs.size(), log->runs.size());
  for (const BearingRunPaths& run : paths.runs) {
    ASSERT_EQ(run.nominal.size(), run.t_s.size());
    ASSERT_EQ(run.calibrated.size(), run.t_s.size());
    ASSERT_EQ(run.bearing.size(), run.t_s.size());
    EXPECT_EQ(run.nominal.front(), run.adjusted.front());  // One start for all three.
    EXPECT_EQ(run.bearing.back() + 1, static_cast<int>(log->runs[run.index].bearings.size()));
  }
  // Run 1 drives a long circle: the nominal wheels end metres off, the calibrated ones close.
  const BearingRunPaths& circle = paths.runs[0];
  const double nominal_gap = (circle.nominal.back() - circle.adjusted.back()).head<2>().norm();
  const double calibrated_gap =
      (circle.calibrated.back() - circle.adjusted.back()).head<2>().norm();
  EXPECT_LT(calibrated_gap, 0.1 * nominal_gap)
      << "calibrated " << calibrated_gap << " m, nominal " << nominal_gap << " m";
}

}  // namespace
}  // namespace calib
