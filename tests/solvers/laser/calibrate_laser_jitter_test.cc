// CalibrateLaser with the interval-jitter step: clean logs keep today's result bit for bit; on
// logs whose boundary stamps jitter, the refit says so and its σ's cover the truth.
#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <gtest/gtest.h>

#include <cmath>

#include "tests/solvers/timing/jittered_log.h"

namespace calib {
namespace {

LaserCalibration Truth(const LaserSimOptions& options) {
  return LaserCalibration{options.odometry, options.base_T_sensor};
}

LaserCalibrationResult Calibrate(const std::vector<LaserInterval>& intervals, bool jitter) {
  LaserCalibrationOptions options;
  options.interval_jitter = jitter;
  StatusOr<LaserCalibrationResult> result = CalibrateLaser(intervals, options);
  EXPECT_TRUE(result.ok()) << result.message();
  return *result;
}

TEST(CalibrateLaserJitterTest, CleanLogKeepsTheBaseResultBitForBit) {
  LaserSimOptions sim;
  sim.num_intervals = 1000;
  sim.seed = 3;
  const LaserLog log = SimulateLaserLog(sim);
  const LaserCalibrationResult base = Calibrate(log.intervals, false);
  const LaserCalibrationResult jitter = Calibrate(log.intervals, true);
  ASSERT_EQ(jitter.interval_jitter.size(), 1u);
  EXPECT_FALSE(jitter.interval_jitter[0].significant) << jitter.interval_jitter[0].p_value;
  EXPECT_FALSE(jitter.jitter_refit);
  EXPECT_EQ(base.estimate.ToVector(), jitter.estimate.ToVector());
  EXPECT_EQ(base.covariance, jitter.covariance);
  EXPECT_EQ(base.noise_sigma[0], jitter.noise_sigma[0]);
  EXPECT_EQ(base.observability.warnings, jitter.observability.warnings);
}

TEST(CalibrateLaserJitterTest, JitteredLogIsRefitAndSaysSo) {
  LaserSimOptions sim;
  sim.num_intervals = 1000;
  sim.seed = 4;
  const LaserLog log = JitteredTupleLog(sim, 0.05);
  const LaserCalibrationResult result = Calibrate(log.intervals, true);
  ASSERT_EQ(result.interval_jitter.size(), 1u);
  const IntervalJitterEstimate& jitter = result.interval_jitter[0];
  EXPECT_TRUE(jitter.significant);
  EXPECT_TRUE(result.jitter_refit);
  EXPECT_LT(std::abs(jitter.jitter_s - 0.05), 3 * jitter.jitter_stddev_s) << jitter.jitter_s;
  bool stated = false;
  for (const std::string& warning : result.observability.warnings) {
    stated = stated || warning.find("only this weaker treatment was possible") != std::string::npos;
  }
  EXPECT_TRUE(stated);
  const LaserParamVector error = result.estimate.ToVector() - Truth(sim).ToVector();
  for (int i = 0; i < kNumLaserParams; ++i) {
    EXPECT_LT(std::abs(error(i)), 3 * result.stddev(i)) << kLaserParamNames[i];
  }
}

// Jittered stamps put noise into the wheel increments, which attenuates the radii: the plain fit's
// 2σ intervals miss them; the refit (whitened per interval, corrected score) covers them.
TEST(CalibrateLaserJitterTest, RefitCoversTheRadiiBetterThanThePlainFit) {
  const int seeds = 8;
  int plain = 0, refit = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    LaserSimOptions sim;
    sim.num_intervals = 600;
    sim.seed = 1000 + seed;
    const LaserLog log = JitteredTupleLog(sim, 0.1);
    const LaserParamVector truth = Truth(sim).ToVector();
    const LaserCalibrationResult a = Calibrate(log.intervals, false);
    const LaserCalibrationResult b = Calibrate(log.intervals, true);
    for (int i : {kLaserRl, kLaserRr, kLaserB}) {
      plain += std::abs(a.estimate.ToVector()(i) - truth(i)) < 2 * a.stddev(i);
      refit += std::abs(b.estimate.ToVector()(i) - truth(i)) < 2 * b.stddev(i);
    }
  }
  EXPECT_GT(refit, plain);
  EXPECT_GE(refit, 0.85 * 3 * seeds);
}

}  // namespace
}  // namespace calib
