#include <calib/core/random.h>
#include <calib/core/timing/stamp_timing.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace calib {
namespace {

// t_k = t0 + k·P + N(0, σ), k = 0..n−1, skipping the indices `drop` says to.
std::vector<double> Grid(int n, double period, double sigma, uint64_t seed,
                         double drop_probability = 0.0) {
  Random random(seed);
  std::vector<double> stamps;
  for (int k = 0; k < n; ++k) {
    const double t = 3.0 + k * period + sigma * random.Normal();
    if (random.Uniform() < drop_probability) continue;
    stamps.push_back(t);
  }
  return stamps;
}

std::string Notes(const StreamTiming& timing) {
  std::string text;
  for (const std::string& note : timing.notes) text += note + "\n";
  return text;
}

TEST(StampTimingTest, PerfectGridHasNoJitter) {
  const StreamTiming t = AnalyzeStreamTiming(Grid(1000, 0.1, 0.0, 1), {}, "odometry", "o.csv");
  EXPECT_EQ(t.stream, "odometry");
  EXPECT_EQ(t.source, "o.csv");
  EXPECT_EQ(t.records, 1000);
  EXPECT_EQ(t.samples, 1000);
  EXPECT_EQ(t.intervals, 999);
  EXPECT_EQ(t.duplicates_dropped, 0);
  EXPECT_EQ(t.repeated_values, 0);
  EXPECT_NEAR(t.period_s, 0.1, 1e-12);
  EXPECT_LT(t.jitter_s, 1e-12);
  EXPECT_EQ(t.gaps, 0);
  EXPECT_EQ(t.longest_gap_s, 0.0);
  EXPECT_EQ(t.multiple_fraction, 0.0);
  EXPECT_TRUE(t.regular);
  EXPECT_FALSE(t.free_running_signature);
  EXPECT_TRUE(t.stamps_are_sample_times);
  ASSERT_FALSE(t.notes.empty());
  EXPECT_NE(t.notes[0].find("o.csv: 1000 samples, period 100 ms"), std::string::npos) << Notes(t);
}

TEST(StampTimingTest, GaussianScatterIsRecovered) {
  for (const double sigma : {0.001, 0.01, 0.017}) {
    SCOPED_TRACE(sigma);
    const double period = sigma == 0.017 ? 0.257 : 0.1;
    const StreamTiming t = AnalyzeStreamTiming(Grid(4000, period, sigma, 2));
    EXPECT_NEAR(t.period_s, period, 0.002 * period);
    EXPECT_NEAR(t.jitter_s, sigma, 0.1 * sigma);
    EXPECT_NEAR(t.pickup_scatter_s, sigma, 0.15 * sigma);
    EXPECT_NEAR(t.interval_correlation, -0.5, 0.06);
    EXPECT_EQ(t.multiple_fraction, 0.0);
    EXPECT_FALSE(t.free_running_signature);
    // 1 % of the period: a regular grid of sample times; 10 % and 6.6 %: pick-up times.
    EXPECT_EQ(t.regular, sigma == 0.001);
    EXPECT_EQ(t.stamps_are_sample_times, sigma == 0.001) << Notes(t);
    if (!t.stamps_are_sample_times) {
      EXPECT_NE(Notes(t).find("they are pick-up times, not sample times"), std::string::npos);
    }
  }
}

TEST(StampTimingTest, MissedSamplesAreMultiplesNotJitter) {
  const std::vector<double> stamps = Grid(5000, 0.1, 0.001, 3, 0.1);
  const StreamTiming t = AnalyzeStreamTiming(stamps);
  int multiples = 0;
  for (size_t k = 0; k + 1 < stamps.size(); ++k) multiples += stamps[k + 1] - stamps[k] > 0.15;
  EXPECT_NEAR(t.multiple_fraction, static_cast<double>(multiples) / (stamps.size() - 1), 1e-12);
  EXPECT_NEAR(t.multiple_fraction, 0.1, 0.02);
  EXPECT_NEAR(t.period_s, 0.1, 1e-4);
  EXPECT_NEAR(t.jitter_s, 0.001, 1e-4);
  EXPECT_TRUE(t.regular);
  EXPECT_FALSE(t.free_running_signature);
  EXPECT_TRUE(t.stamps_are_sample_times);
  EXPECT_NE(Notes(t).find("missed samples"), std::string::npos) << Notes(t);
}

TEST(StampTimingTest, DriftingClockDoesNotInflateTheJitter) {
  Random random(4);
  std::vector<double> stamps;
  double clock = 0.0;
  for (int k = 0; k < 5000; ++k) {
    clock += 0.1 * (1.0 + 0.02 * k / 5000.0);  // The period drifts by 2 % over the log.
    stamps.push_back(clock + 0.0005 * random.Normal());
  }
  const StreamTiming t = AnalyzeStreamTiming(stamps);
  EXPECT_NEAR(t.jitter_s, 0.0005, 0.05e-3);
  EXPECT_NEAR(t.period_s, 0.101, 0.0002);
  EXPECT_TRUE(t.regular);
  EXPECT_TRUE(t.stamps_are_sample_times);
}

TEST(StampTimingTest, GapsAreCountedApart) {
  std::vector<double> stamps = Grid(3000, 0.1, 0.001, 5);
  for (size_t k = 1000; k < stamps.size(); ++k) stamps[k] += 2.0;  // A 2.1 s interval.
  for (size_t k = 2000; k < stamps.size(); ++k) stamps[k] += 0.5;  // 0.6 s.
  const StreamTiming t = AnalyzeStreamTiming(stamps);
  EXPECT_EQ(t.gaps, 2);
  EXPECT_NEAR(t.longest_gap_s, 2.1, 0.01);
  EXPECT_EQ(t.multiple_fraction, 0.0);
  EXPECT_NEAR(t.jitter_s, 0.001, 1e-4);
  EXPECT_NE(Notes(t).find("2 gap(s) longer than 5 periods"), std::string::npos) << Notes(t);
}

// The matched pose of sensor sample i: steady motion plus a small error of that sample (kept
// when the sample is picked up again).
double SamplePosition(double speed, double period, double sample_time) {
  const double i = std::round(sample_time / period);
  return speed * sample_time + 1e-4 * std::sin(1e3 * i);
}

// A sensor free-running at 99.5 ms; a 100 ms logger (pick-up jitter 2 ms) stamps the latest
// sample with its own pick-up time. The stamps look regular, the values repeat.
TEST(StampTimingTest, FreeRunningSensorPickedUpByALogger) {
  Random random(6);
  const double sensor_period = 0.0995, speed = 0.2;  // m/s along x.
  std::vector<double> stamps, values;
  for (int j = 0; j < 3000; ++j) {
    const double pickup = 0.1 * j + 0.002 * random.Normal() + 0.05;
    const double sample_time = std::floor(pickup / sensor_period) * sensor_period;
    stamps.push_back(pickup);
    values.insert(values.end(), {SamplePosition(speed, sensor_period, sample_time), 0.0, 0.0});
  }
  const StreamTiming t = AnalyzeStreamTiming(stamps, values, "sensor_poses", "poses.csv");
  EXPECT_NEAR(t.period_s, 0.1, 1e-3);
  EXPECT_LT(t.jitter_s, 0.003);
  EXPECT_GE(t.repeated_values, 2);
  EXPECT_TRUE(t.step_multiples_detected);
  EXPECT_GT(t.step_multiple_fraction, 0.0);
  EXPECT_TRUE(t.free_running_signature);
  EXPECT_FALSE(t.stamps_are_sample_times);
  EXPECT_NE(Notes(t).find("held sample picked up again"), std::string::npos) << Notes(t);

  // A logger without jitter, 0.5 % slower than the sensor: it never holds a sample and skips one
  // in 200. Only the steps show it (a skip at one window's edge lies inside the next window).
  stamps.clear();
  values.clear();
  for (int j = 0; j < 3000; ++j) {
    const double pickup = 0.1 * j + 0.05;
    stamps.push_back(pickup);
    const double sample_time = std::floor(pickup / sensor_period) * sensor_period;
    values.insert(values.end(), {SamplePosition(speed, sensor_period, sample_time), 0.0, 0.0});
  }
  const StreamTiming skips = AnalyzeStreamTiming(stamps, values);
  EXPECT_EQ(skips.repeated_values, 0);
  EXPECT_NEAR(skips.step_multiple_fraction, 0.005, 0.001);
  EXPECT_TRUE(skips.step_multiples_detected);
  EXPECT_FALSE(skips.stamps_are_sample_times);

  // The same sensor logged only when a new sample is there, at polls every 257 ms: the
  // intervals (and the steps) come in 2 or 3 sensor periods.
  stamps.clear();
  values.clear();
  double last = -1.0;
  for (int j = 0; j < 1000; ++j) {
    const double pickup = 0.257 * j + 0.017 * random.Normal() + 0.3;
    const double sample_time = std::floor(pickup / sensor_period) * sensor_period;
    if (sample_time == last) continue;
    last = sample_time;
    stamps.push_back(sample_time);
    values.insert(values.end(), {SamplePosition(speed, sensor_period, sample_time), 0.0, 0.0});
  }
  const StreamTiming c = AnalyzeStreamTiming(stamps, values);
  EXPECT_NEAR(c.period_s, sensor_period, 1e-4);
  EXPECT_GT(c.multiple_fraction, 0.9);
  EXPECT_TRUE(c.step_multiples_detected);
  EXPECT_TRUE(c.free_running_signature);
  EXPECT_FALSE(c.stamps_are_sample_times);
  EXPECT_NE(Notes(c).find("cluster at whole multiples"), std::string::npos) << Notes(c);
}

// The simulator's stamps: exact sample times of an irregular sampler, intervals 0.8 s ± 0.02
// uniform and independent. Their local grid scatter is the random walk of the intervals (not
// regular), but the intervals are uncorrelated: taken as sample times, no signature.
TEST(StampTimingTest, IrregularExactStampsAreSampleTimes) {
  Random random(7);
  std::vector<double> stamps = {0.0};
  for (int k = 0; k < 2000; ++k) stamps.push_back(stamps.back() + random.Uniform(0.78, 0.82));
  const StreamTiming t = AnalyzeStreamTiming(stamps);
  EXPECT_NEAR(t.period_s, 0.8, 0.002);
  EXPECT_NEAR(t.interval_correlation, 0.0, 0.08);
  EXPECT_EQ(t.multiple_fraction, 0.0);
  EXPECT_FALSE(t.regular);
  EXPECT_FALSE(t.free_running_signature);
  EXPECT_TRUE(t.stamps_are_sample_times);
  EXPECT_NE(Notes(t).find("taken as sample times"), std::string::npos) << Notes(t);
}

TEST(StampTimingTest, ExactDuplicatesAreDroppedAndCounted) {
  std::vector<double> stamps, values;
  for (int k = 0; k < 100; ++k) {
    for (int copy = 0; copy < (k % 10 == 0 ? 2 : 1); ++copy) {
      stamps.push_back(0.1 * k);
      values.insert(values.end(), {0.01 * k, -0.02 * k});
    }
  }
  const StreamTiming t = AnalyzeStreamTiming(stamps, values);
  EXPECT_EQ(t.records, 110);
  EXPECT_EQ(t.samples, 100);
  EXPECT_EQ(t.duplicates_dropped, 10);
  EXPECT_LT(t.jitter_s, 1e-12);
  EXPECT_EQ(t.repeated_values, 0);
  EXPECT_NE(Notes(t).find("10 exact duplicate record(s)"), std::string::npos) << Notes(t);
}

TEST(StampTimingTest, RestAndQuantizedEncodersAreNotHeldSamples) {
  // Quantized encoder at a slow 0.7 tick per sample, then at rest, then moving again.
  std::vector<double> stamps, values;
  for (int k = 0; k < 600; ++k) {
    const double ticks = k < 200 ? std::floor(0.7 * k) : k < 400 ? 139.0 : 139 + (k - 400) * 3;
    stamps.push_back(0.05 * k);
    values.insert(values.end(), {ticks * 0.001, ticks * 0.002});
  }
  const StreamTiming t = AnalyzeStreamTiming(stamps, values, "odometry");
  EXPECT_TRUE(t.values_quantized);
  EXPECT_EQ(t.repeated_values, 0);
  EXPECT_FALSE(t.free_running_signature);
  EXPECT_TRUE(t.stamps_are_sample_times);
}

TEST(StampTimingTest, DisplacementSteps) {
  const std::vector<double> none(201, 0.0);  // Stamps are not used.
  std::vector<double> steady(200, 0.01);
  for (size_t k = 0; k < steady.size(); ++k) steady[k] *= 1.0 + 0.03 * std::sin(0.1 * k);
  StepMultiples s = AnalyzeDisplacementSteps(none, steady);
  EXPECT_EQ(s.steady_steps, 200);
  EXPECT_EQ(s.multiple_fraction, 0.0);
  EXPECT_FALSE(s.detected);

  std::vector<double> held = steady;
  for (size_t k = 13; k + 1 < held.size(); k += 40) {
    held[k] = 0.0;
    held[k + 1] *= 2.0;
  }
  s = AnalyzeDisplacementSteps(none, held);
  EXPECT_EQ(s.zero_steps, 5);
  EXPECT_EQ(s.multi_steps, 5);
  EXPECT_NEAR(s.multiple_fraction, 10.0 / s.steady_steps, 1e-12);
  EXPECT_TRUE(s.detected);

  // Speeds that switch at once every 7 steps (as the simulator's segments), intervals ±2.5 %: a
  // step to 2/3 or 1/2 of the last fits a multiple of a third or a half of it, but the new level
  // stays; no skip or hold is there.
  std::vector<double> switching;
  const double levels[] = {0.3, 0.2, 0.3, 0.15, 0.45, 0.3};
  for (int k = 0; k < 700; ++k) {
    switching.push_back(levels[(k / 7) % 6] * (1.0 + 0.025 * std::sin(1.7 * k)));
  }
  s = AnalyzeDisplacementSteps(std::vector<double>(701, 0.0), switching);
  EXPECT_EQ(s.multiple_fraction, 0.0);
  EXPECT_FALSE(s.detected);

  // Starting from rest and accelerating: no steady window holds a held sample.
  std::vector<double> start(200, 0.0);
  for (size_t k = 100; k < start.size(); ++k) start[k] = 0.001 * std::min<size_t>(k - 99, 20);
  s = AnalyzeDisplacementSteps(none, start);
  EXPECT_EQ(s.zero_steps, 0);
  EXPECT_FALSE(s.detected);
}

TEST(StampTimingTest, PoolsRuns) {
  const StreamTiming a = AnalyzeStreamTiming(Grid(1000, 0.1, 0.001, 8), {}, "bearings", "run 1");
  const StreamTiming b = AnalyzeStreamTiming(Grid(3000, 0.1, 0.002, 9), {}, "bearings", "run 2");
  const StreamTiming p = PoolStreamTiming({a, b}, "bearings", "bearings.csv");
  EXPECT_EQ(p.records, 4000);
  EXPECT_EQ(p.samples, 4000);
  EXPECT_EQ(p.intervals, a.intervals + b.intervals);
  EXPECT_NEAR(p.period_s, 0.1, 1e-4);
  EXPECT_NEAR(p.jitter_s,
              std::sqrt((1000 * a.jitter_s * a.jitter_s + 3000 * b.jitter_s * b.jitter_s) / 4000),
              1e-15);
  EXPECT_TRUE(p.stamps_are_sample_times);
  EXPECT_NE(Notes(p).find("pooled over 2 run(s)"), std::string::npos) << Notes(p);
}

// Stamps in ms, µs or ns (a bag exported as integers, a logger's own clock) are named, with the
// divisor; seconds pass, whatever the epoch, and so do slow streams within 10 s a step.
TEST(StampTimingTest, StampsInAnotherUnitAreNamed) {
  std::vector<double> seconds;
  for (int k = 0; k < 100; ++k) seconds.push_back(1.7e9 + 0.02 * k);
  EXPECT_TRUE(CheckStampUnit(seconds, "odometry.csv").ok());
  const struct {
    double scale;
    const char* words;
  } cases[] = {{1e3, "milliseconds (divide t by 1e+03)"},
               {1e6, "microseconds (divide t by 1e+06)"},
               {1e9, "nanoseconds (divide t by 1e+09)"}};
  for (const auto& c : cases) {
    std::vector<double> scaled;
    for (int k = 0; k < 100; ++k) scaled.push_back(c.scale * 0.02 * k);
    const Status status = CheckStampUnit(scaled, "odometry.csv");
    ASSERT_FALSE(status.ok()) << c.words;
    EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
    EXPECT_NE(status.message().find("odometry.csv: the stamps step by"), std::string::npos);
    EXPECT_NE(status.message().find(c.words), std::string::npos) << status.message();
  }
  // Nanoseconds since 1970 step like seconds would at 0.02 ns: the epoch names them.
  std::vector<double> epoch_ns;
  for (int k = 0; k < 100; ++k) epoch_ns.push_back(1.7e18 + 2e7 * k);
  EXPECT_NE(CheckStampUnit(epoch_ns, "scans.csv").message().find("nanoseconds"), std::string::npos);
  std::vector<double> slow;
  for (int k = 0; k < 100; ++k) slow.push_back(5.0 * k);
  EXPECT_TRUE(CheckStampUnit(slow, "bearings.csv").ok());
}

TEST(StampTimingTest, DropExactDuplicatesNamesBothLines) {
  StreamRecords records;
  records.stamps_s = {3.0, 3.2, 3.2, 3.4};
  records.values = {0, 0, 1, 1, 1, 1, 2, 2};
  records.lines = {10, 12, 13, 14};
  records.value_names = {"left", "right"};
  int dropped = 0;
  ASSERT_TRUE(DropExactDuplicates("odometry.csv", &records, &dropped).ok());
  EXPECT_EQ(dropped, 1);
  EXPECT_EQ(records.stamps_s, (std::vector<double>{3.0, 3.2, 3.4}));
  EXPECT_EQ(records.lines, (std::vector<int>{10, 12, 14}));
  EXPECT_EQ(records.values, (std::vector<double>{0, 0, 1, 1, 2, 2}));

  records.stamps_s = {3.0, 3.2, 3.2};
  records.values = {0, 0, 1, 1, 1, 1.5};
  records.lines = {10, 12, 13};
  const Status status = DropExactDuplicates("odometry.csv", &records);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  EXPECT_EQ(status.message(), "odometry.csv: line 12 and line 13 share t=3.2 but differ in right");
}

}  // namespace
}  // namespace calib
