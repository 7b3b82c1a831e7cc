#include <calib/core/laser/laser_simulator.h>
#include <calib/core/timing/logging_model.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <vector>

namespace calib {
namespace {

LaserSimOptions Options(int intervals) {
  LaserSimOptions options;
  options.num_intervals = intervals;
  options.mean_interval_s = 0.1;
  options.interval_jitter_s = 0.01;
  options.seed = 3;
  return options;
}

// The robot-like pattern of the issue: a scanner free-running at 99.5 ms stamped at a 100 ms
// logger's pick-up, encoders polled every 257 ms with 17 ms of stamp scatter.
LoggingModel RobotLike() {
  LoggingModel model;
  model.sensor_period_s = 0.0995;
  model.sensor_phase_s = 0.013;
  model.sensor_clock_drift = 2e-4;
  model.logger_period_s = 0.1;
  model.logger_jitter_s = 0.004;
  model.pickup_latency_s = 0.002;
  model.encoder_period_s = 0.257;
  model.encoder_poll_jitter_s = 0.005;
  model.encoder_stamp_jitter_s = 0.017;
  return model;
}

double StdDev(const std::vector<double>& x) {
  double mean = 0.0, square = 0.0;
  for (double v : x) mean += v / x.size();
  for (double v : x) square += (v - mean) * (v - mean) / (x.size() - 1);
  return std::sqrt(square);
}

TEST(LoggingModelTest, CleanModelGivesTheUnloggedStreams) {
  LaserSimOptions options = Options(500);
  options.encoder_ticks_per_rad = 1000.0;
  LaserSimTruth truth;
  LoggedTimingTruth timing;
  const LaserStreams logged = SimulateLoggedLaserStreams(options, LoggingModel(), &truth, &timing);
  const LaserStreams plain = SimulateLaserStreams(options, 0.0);
  ASSERT_EQ(logged.odometry.size(), plain.odometry.size());
  ASSERT_EQ(logged.sensor_poses.size(), plain.sensor_poses.size());
  for (size_t k = 0; k < plain.odometry.size(); ++k) {
    EXPECT_EQ(logged.odometry[k].t_s, plain.odometry[k].t_s) << k;
    EXPECT_EQ(logged.odometry[k].left_rad, plain.odometry[k].left_rad) << k;
    EXPECT_EQ(logged.odometry[k].right_rad, plain.odometry[k].right_rad) << k;
    EXPECT_EQ(timing.encoder_sample_time_s[k], plain.odometry[k].t_s) << k;
  }
  for (size_t k = 0; k < plain.sensor_poses.size(); ++k) {
    EXPECT_EQ(logged.sensor_poses[k].t_s, plain.sensor_poses[k].t_s) << k;
    EXPECT_EQ(logged.sensor_poses[k].world_T_sensor, plain.sensor_poses[k].world_T_sensor) << k;
    EXPECT_EQ(timing.sensor_sample_time_s[k], plain.sensor_poses[k].t_s) << k;
  }
  EXPECT_EQ(timing.sensor_duplicates + timing.encoder_duplicates + timing.skipped_samples +
                timing.held_samples,
            0u);
}

// Pick-ups stamp late, never early; a sample written twice carries exactly the same pose; the
// logger slower than the sensor skips samples, a faster one holds them.
TEST(LoggingModelTest, PickupsStampTheLatestSampleLate) {
  for (const double logger_period : {0.1, 0.09}) {
    LoggingModel model = RobotLike();
    model.logger_period_s = logger_period;
    LoggedTimingTruth timing;
    const LaserStreams streams = SimulateLoggedLaserStreams(Options(1000), model, nullptr, &timing);
    const std::vector<double> samples = FreeRunningSampleTimes(model, 1001);
    ASSERT_EQ(timing.all_sensor_sample_times_s, samples);
    ASSERT_EQ(timing.sensor_sample_time_s.size(), streams.sensor_poses.size());
    for (size_t k = 0; k < streams.sensor_poses.size(); ++k) {
      const size_t sample = timing.sensor_sample_index[k];
      EXPECT_EQ(timing.sensor_sample_time_s[k], samples[sample]);
      EXPECT_GE(streams.sensor_poses[k].t_s, samples[sample] + model.pickup_latency_s) << k;
      // The latest sample: the next one was not yet available at the pick-up.
      if (sample + 1 < samples.size()) {
        EXPECT_LT(streams.sensor_poses[k].t_s, samples[sample + 1] + model.pickup_latency_s);
      }
      if (k > 0 && timing.sensor_sample_index[k - 1] == sample) {
        EXPECT_EQ(streams.sensor_poses[k].world_T_sensor,
                  streams.sensor_poses[k - 1].world_T_sensor);
        EXPECT_GT(streams.sensor_poses[k].t_s, streams.sensor_poses[k - 1].t_s);
      }
    }
    if (logger_period > model.sensor_period_s) {
      EXPECT_GT(timing.skipped_samples, 0u);
    } else {
      EXPECT_GT(timing.held_samples, 50u);
    }
  }
}

// Without pick-up jitter a logger slower than the sensor never writes a sample twice.
TEST(LoggingModelTest, SteadySlowLoggerOnlySkips) {
  LoggingModel model = RobotLike();
  model.logger_jitter_s = 0.0;
  LoggedTimingTruth timing;
  SimulateLoggedLaserStreams(Options(1000), model, nullptr, &timing);
  EXPECT_EQ(timing.held_samples, 0u);
  // A skip every 1/(1/0.0995 − 1/0.1) ≈ 20 s, i.e. about 5 in 100 s.
  EXPECT_GE(timing.skipped_samples, 3u);
  EXPECT_LE(timing.skipped_samples, 7u);
}

// Encoder polls scatter about j·P with the poll σ; stamps scatter about the true polls with the
// stamp σ; the wheel angles are those at the true times (the clean simulation's, when polled at
// the scan times).
TEST(LoggingModelTest, EncoderScatterHasTheRequestedSigma) {
  LoggingModel model = RobotLike();
  LoggedTimingTruth timing;
  const LaserStreams streams = SimulateLoggedLaserStreams(Options(3000), model, nullptr, &timing);
  ASSERT_GT(streams.odometry.size(), 1000u);
  std::vector<double> stamp_error, poll_error;
  for (size_t j = 0; j < streams.odometry.size(); ++j) {
    const double true_s = timing.encoder_sample_time_s[j];
    stamp_error.push_back(streams.odometry[j].t_s - true_s);
    poll_error.push_back(std::remainder(true_s, model.encoder_period_s));
    if (j > 0) {
      EXPECT_GT(streams.odometry[j].t_s, streams.odometry[j - 1].t_s);
    }
  }
  const double n = static_cast<double>(stamp_error.size());
  // The σ estimate of n normal draws has a relative σ of 1/√(2n): allow 4 of those.
  EXPECT_NEAR(StdDev(stamp_error), model.encoder_stamp_jitter_s,
              4.0 * model.encoder_stamp_jitter_s / std::sqrt(2.0 * n));
  EXPECT_NEAR(StdDev(poll_error), model.encoder_poll_jitter_s,
              4.0 * model.encoder_poll_jitter_s / std::sqrt(2.0 * n));

  LoggingModel stamps_only;
  stamps_only.encoder_stamp_jitter_s = 0.003;
  const LaserStreams jittered = SimulateLoggedLaserStreams(Options(500), stamps_only);
  const LaserStreams clean = SimulateLaserStreams(Options(500), 0.0);
  ASSERT_EQ(jittered.odometry.size(), clean.odometry.size());
  for (size_t j = 0; j < clean.odometry.size(); ++j) {
    EXPECT_EQ(jittered.odometry[j].left_rad, clean.odometry[j].left_rad);
    EXPECT_EQ(jittered.odometry[j].right_rad, clean.odometry[j].right_rad);
  }
}

// Exact duplicate rows appear at the requested rate in both streams.
TEST(LoggingModelTest, DuplicatesAtTheRequestedRate) {
  LoggingModel model = RobotLike();
  model.repeat_fraction = 0.05;
  LoggedTimingTruth timing;
  const LaserStreams streams = SimulateLoggedLaserStreams(Options(4000), model, nullptr, &timing);
  size_t pose_duplicates = 0, encoder_duplicates = 0;
  for (size_t k = 1; k < streams.sensor_poses.size(); ++k) {
    const StampedPose& a = streams.sensor_poses[k - 1];
    const StampedPose& b = streams.sensor_poses[k];
    pose_duplicates += a.t_s == b.t_s && a.world_T_sensor == b.world_T_sensor;
  }
  for (size_t k = 1; k < streams.odometry.size(); ++k) {
    const EncoderSample& a = streams.odometry[k - 1];
    const EncoderSample& b = streams.odometry[k];
    encoder_duplicates += a.t_s == b.t_s && a.left_rad == b.left_rad && a.right_rad == b.right_rad;
  }
  EXPECT_EQ(pose_duplicates, timing.sensor_duplicates);
  EXPECT_EQ(encoder_duplicates, timing.encoder_duplicates);
  // Binomial counts over the distinct rows: within 4 σ of the rate.
  const auto expect_rate = [&](size_t count, size_t rows) {
    const double distinct = static_cast<double>(rows - count);
    const double sigma = std::sqrt(distinct * 0.05 * 0.95);
    EXPECT_NEAR(static_cast<double>(count), 0.05 * distinct, 4.0 * sigma);
  };
  expect_rate(pose_duplicates, streams.sensor_poses.size());
  expect_rate(encoder_duplicates, streams.odometry.size());
}

TEST(LoggingModelTest, RejectsBadFields) {
  EXPECT_TRUE(ValidateLoggingModel(RobotLike()).ok());
  LoggingModel model = RobotLike();
  model.logger_period_s = -0.1;
  EXPECT_NE(ValidateLoggingModel(model).message().find("logger_period_s"), std::string::npos);
  model = RobotLike();
  model.encoder_stamp_jitter_s = 0.05;  // Above 0.08·257 ms.
  EXPECT_NE(ValidateLoggingModel(model).message().find("encoder_stamp_jitter_s"),
            std::string::npos);
  model = RobotLike();
  model.repeat_fraction = 0.6;
  EXPECT_EQ(ValidateLoggingModel(model).code(), StatusCode::kInvalidInput);
  model = RobotLike();
  model.sensor_clock_drift = NAN;
  EXPECT_FALSE(ValidateLoggingModel(model).ok());
  model = LoggingModel();
  model.sensor_phase_s = 0.01;  // Without a free-running sensor.
  EXPECT_FALSE(ValidateLoggingModel(model).ok());
}

}  // namespace
}  // namespace calib
