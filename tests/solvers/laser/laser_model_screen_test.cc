#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/scan/scan_simulator.h>
#include <calib/solvers/laser/laser_model_screen.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace calib {
namespace {

// A long log of integer encoder counts (2764.8 a turn, each poll rounded): the rounding is noise
// in the wheel speeds. Binned by its own speeds, an interval's residual follows that noise
// (errors in the regressor), and the screen had flagged "the residuals still depend on angular
// rate" on clean logs of this length (p ≈ 1e-8). Binned by the speeds over the interval and its
// two neighbours, whose errors are the window ends' own, nothing is flagged.
TEST(LaserModelScreen, RoundedEncoderCountsAreNoPhysicsLeftOut) {
  LaserSimOptions options = DefaultScanLaserOptions();  // 0.1 m wheels, 0.5 m apart, 10 Hz.
  options.scan_noise_sigma = Eigen::Vector3d(0.0012, 0.0012, 0.00035);
  options.num_intervals = 13000;
  options.seed = 5;
  LaserSimTruth truth;
  LaserStreams streams = SimulateLaserStreams(options, 0.0, &truth);
  const double per_count = 2.0 * M_PI / 2764.8;
  for (EncoderSample& s : streams.odometry) {
    s.left_rad = per_count * std::round(s.left_rad / per_count);
    s.right_rad = per_count * std::round(s.right_rad / per_count);
  }
  const StatusOr<LaserLog> log = LaserLogFromStreams(streams.odometry, streams.sensor_poses, "sim");
  ASSERT_TRUE(log.ok()) << log.message();
  const StatusOr<LaserModelScreen> screen =
      ScreenLaserModel(log->intervals, LaserCalibrationOptions(), true);
  ASSERT_TRUE(screen.ok()) << screen.message();
  std::printf("%zu intervals: %s\n%s\n", log->intervals.size(), screen->structure.c_str(),
              screen->warning.c_str());
  EXPECT_TRUE(screen->structure.empty()) << screen->structure;
}

}  // namespace
}  // namespace calib
