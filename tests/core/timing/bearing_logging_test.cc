// The bearing simulator under the logging model (core/timing/logging_model.h).
#include <calib/core/bearing/bearing_simulator.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace calib {
namespace {

BearingSimOptions Options() {
  BearingSimOptions options;
  options.runs = {WeavingRun(300.0)};
  options.bearing_noise_rad = 0.01;
  options.seed = 5;
  return options;
}

// All logging fields zero: the log of the plain simulator, bit for bit.
TEST(BearingLoggingTest, CleanModelChangesNothing) {
  BearingSimOptions options;  // Martinelli's three runs.
  options.bearing_noise_rad = 0.01;
  const BearingLog plain = SimulateBearingLog(options);
  options.logging = LoggingModel();
  BearingSimTruth truth;
  const BearingLog logged = SimulateBearingLog(options, &truth);
  ASSERT_EQ(plain.runs.size(), logged.runs.size());
  for (size_t i = 0; i < plain.runs.size(); ++i) {
    ASSERT_EQ(plain.runs[i].odometry.size(), logged.runs[i].odometry.size());
    ASSERT_EQ(plain.runs[i].bearings.size(), logged.runs[i].bearings.size());
    for (size_t k = 0; k < plain.runs[i].odometry.size(); ++k) {
      EXPECT_EQ(plain.runs[i].odometry[k].t_s, logged.runs[i].odometry[k].t_s);
      EXPECT_EQ(plain.runs[i].odometry[k].left_rad, logged.runs[i].odometry[k].left_rad);
    }
    for (size_t k = 0; k < plain.runs[i].bearings.size(); ++k) {
      EXPECT_EQ(plain.runs[i].bearings[k].t_s, logged.runs[i].bearings[k].t_s);
      EXPECT_EQ(plain.runs[i].bearings[k].bearing_rad, logged.runs[i].bearings[k].bearing_rad);
    }
    EXPECT_EQ(truth.runs[i].timing.sensor_sample_time_s.size(), plain.runs[i].bearings.size());
  }
}

// A free-running bearing sensor picked up late by a slower logger, encoder polls with scatter:
// every bearing row is stamped at or after its sample's true time, held rows repeat the bearing,
// the encoder stamps scatter with the requested σ about the true polls.
TEST(BearingLoggingTest, BearingsPickedUpLateEncodersScattered) {
  BearingSimOptions options = Options();
  options.logging.sensor_period_s = 0.95;
  options.logging.sensor_phase_s = 0.2;
  options.logging.logger_period_s = 0.9;  // Faster than the sensor: samples held.
  options.logging.logger_jitter_s = 0.02;
  options.logging.encoder_period_s = 0.05;
  options.logging.encoder_poll_jitter_s = 0.002;
  options.logging.encoder_stamp_jitter_s = 0.003;
  BearingSimTruth truth;
  const BearingLog log = SimulateBearingLog(options, &truth);
  const BearingRun& run = log.runs[0];
  const LoggedTimingTruth& timing = truth.runs[0].timing;
  const double start = options.start_time_s;  // The run's start on the log's clock.
  ASSERT_EQ(run.bearings.size(), timing.sensor_sample_time_s.size());
  for (size_t k = 0; k < run.bearings.size(); ++k) {
    EXPECT_GE(run.bearings[k].t_s - start, timing.sensor_sample_time_s[k]) << k;
    if (k > 0 && timing.sensor_sample_index[k] == timing.sensor_sample_index[k - 1]) {
      EXPECT_EQ(run.bearings[k].bearing_rad, run.bearings[k - 1].bearing_rad);
    }
  }
  EXPECT_GT(timing.held_samples, 10u);
  ASSERT_EQ(run.odometry.size(), timing.encoder_sample_time_s.size());
  double sum2 = 0.0;
  // The first and last rows (the run's start and end) are exact; the others are polls.
  for (size_t k = 1; k + 1 < run.odometry.size(); ++k) {
    const double e = run.odometry[k].t_s - timing.encoder_sample_time_s[k];
    sum2 += e * e;
    EXPECT_GT(run.odometry[k].t_s, run.odometry[k - 1].t_s);
  }
  const double n = static_cast<double>(run.odometry.size() - 2);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.003, 4.0 * 0.003 / std::sqrt(2.0 * n));
}

}  // namespace
}  // namespace calib
