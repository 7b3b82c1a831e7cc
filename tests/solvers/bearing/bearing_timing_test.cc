// The bearing calibration's timing model (solvers/bearing/bearing_timing.h): the clock offset and
// the stamp jitter are kept only when the data ask for them, clean logs keep the plain answer bit
// for bit, and on jittered stamps the timing-aware estimate is honest where the plain one is not.
#include <calib/core/bearing/bearing_log_io.h>
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/core/random.h>
#include <calib/solvers/bearing/bearing_clock.h>
#include <calib/solvers/bearing/bearing_timing.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace calib {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;

double ParamError(int i, double estimate, double truth) {
  return i < 2 ? WrapAngle(estimate - truth) : estimate - truth;
}

// A simulated log whose bearing stamps scatter: the bearing taken at t is stamped t − ε,
// ε ~ N(0, σ_t²) (kept within ±0.4 s so that the stamps stay in order and in the runs).
BearingLog JitteredLog(const BearingSimOptions& o, double jitter_s, uint64_t seed,
                       BearingSimTruth* truth) {
  BearingLog log = SimulateBearingLog(o, truth);
  std::mt19937_64 rng(seed * 7919 + 13);
  std::normal_distribution<double> normal(0.0, jitter_s);
  for (BearingRun& run : log.runs) {
    const double first = run.odometry.front().t_s, last = run.odometry.back().t_s;
    for (BearingSample& b : run.bearings) {
      b.t_s = std::clamp(b.t_s - std::clamp(normal(rng), -0.4, 0.4), first, last);
    }
  }
  return log;
}

BearingSimOptions JitterScene(uint64_t seed) {
  BearingSimOptions o;  // Martinelli's §8.1 circles, a precise bearing sensor.
  o.seed = seed;
  o.encoder_rate_hz = 5.0;
  o.bearing_noise_rad = 0.2 * kDeg;
  o.initial_distance_run = 1;
  return o;
}

// Largest |error|/σ over the five parameters.
double WorstSigmas(const BearingCalibrationResult& r, const BearingSimTruth& truth) {
  const BearingParamVector e = ToVector(r.estimate), t = ToVector(truth.params);
  double worst = 0.0;
  for (int i = 0; i < kNumBearingParams; ++i) {
    worst = std::max(worst, std::abs(ParamError(i, e(i), t(i))) / r.stddev(i));
  }
  return worst;
}

BearingCalibrationOptions Plain() {
  BearingCalibrationOptions options;
  options.timing.time_offset = false;
  options.timing.stamp_jitter = false;
  options.timing.sensor_clock = false;
  return options;
}

// Encoder polls stamped with scatter (the true sample at stamp + ε), kept in order.
BearingLog JitteredEncoderLog(const BearingSimOptions& o, double jitter_s, uint64_t seed,
                              BearingSimTruth* truth) {
  BearingLog log = SimulateBearingLog(o, truth);
  std::mt19937_64 rng(seed * 104729 + 7);
  std::normal_distribution<double> normal(0.0, jitter_s);
  const double bound = 0.45 / o.encoder_rate_hz;
  for (BearingRun& run : log.runs) {
    std::vector<EncoderSample>& odo = run.odometry;
    for (size_t k = 1; k + 1 < odo.size(); ++k) {
      const double t = odo[k].t_s - std::clamp(normal(rng), -bound, bound);
      odo[k].t_s = std::clamp(t, odo[k - 1].t_s + 1e-3, odo[k + 1].t_s - 1e-3);
    }
  }
  return log;
}

BearingLog ReadData(const std::string& relative) {
  const StatusOr<BearingLog> log = ReadBearingLog((fs::path(CALIB_SOURCE_DIR) / relative).string());
  EXPECT_TRUE(log.ok()) << log.message();
  return log.ok() ? *log : BearingLog{};
}

// Errors e_k ~ N(0, σβ² + σt²·g_k²) with known rates: the profile likelihood recovers σt within
// 3σ and rejects σt = 0; with σt = 0 it does not.
TEST(BearingTimingTest, ProfileLikelihoodRecoversTheJitter) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-0.3, 0.3);
  for (double jitter : {0.0, 0.05}) {
    std::vector<double> e, g;
    for (int k = 0; k < 3000; ++k) {
      g.push_back(uniform(rng));
      e.push_back(normal(rng) * std::sqrt(1e-4 + jitter * jitter * g.back() * g.back()));
    }
    const BearingJitterEstimate est = EstimateBearingJitter(e, g, 1.0, 0.01);
    if (jitter == 0.0) {
      EXPECT_FALSE(est.significant) << est.p_value;
    } else {
      EXPECT_TRUE(est.significant) << est.p_value;
      EXPECT_LE(std::abs(est.jitter_s - jitter), 3.0 * est.jitter_stddev_s)
          << est.jitter_s << " ± " << est.jitter_stddev_s;
      EXPECT_NEAR(est.bearing_sigma_rad, 1e-2, 1e-3);
    }
  }
}

// A clean log: both tests run, neither is kept, and the estimate is the plain one bit for bit.
TEST(BearingTimingTest, CleanLogKeepsThePlainAnswerBitForBit) {
  const BearingLog log = ReadData("data/diagnose/bearing_clean");
  const StatusOr<BearingCalibrationResult> plain = CalibrateBearing(log, Plain());
  const StatusOr<BearingCalibrationResult> aware = CalibrateBearing(log);
  ASSERT_TRUE(plain.ok() && aware.ok());
  EXPECT_TRUE(aware->timing.time_offset_tested);
  EXPECT_TRUE(aware->timing.jitter_tested);
  EXPECT_EQ(aware->timing.treatment, "stamps as sample times");
  EXPECT_EQ(aware->timing.time_offset_s, 0.0);
  EXPECT_GT(aware->timing.time_offset_stddev_s, 0.0);
  for (int i = 0; i < kNumBearingParams; ++i) {
    EXPECT_EQ(ToVector(aware->estimate)(i), ToVector(plain->estimate)(i)) << kBearingParamNames[i];
    // ceres::Covariance orders blocks by address: equal to round-off even between two runs.
    EXPECT_NEAR(aware->stddev(i), plain->stddev(i), 1e-12 * plain->stddev(i))
        << kBearingParamNames[i];
  }
  for (int i = 0; i < kNumBearingMetricParams; ++i) {
    EXPECT_EQ(ToVector(aware->metric)(i), ToVector(plain->metric)(i)) << kBearingMetricNames[i];
  }
}

// The concealed 150 ms offset of data/diagnose/bearing_time_offset: calibrate models it, τ and
// every parameter within 3σ of the truth (the plain fit has a parameter ≥ 3σ off).
TEST(BearingTimingTest, ClockOffsetIsPartOfTheCalibration) {
  const BearingLog log = ReadData("data/diagnose/bearing_time_offset");
  const StatusOr<BearingCalibrationResult> r = CalibrateBearing(log);
  ASSERT_TRUE(r.ok()) << r.message();
  EXPECT_TRUE(r->timing.time_offset_modelled) << r->timing.statement;
  EXPECT_EQ(r->timing.treatment, "clock offset modelled");
  EXPECT_LE(std::abs(r->timing.time_offset_s - 0.15), 3.0 * r->timing.time_offset_stddev_s)
      << r->timing.time_offset_s << " ± " << r->timing.time_offset_stddev_s;
  BearingSimTruth truth;
  truth.params = BearingParams{0.0, M_PI / 2.0, 1.65, 1.006 / 0.99, 0.99 / (0.5 * 0.97)};
  EXPECT_LE(WorstSigmas(*r, truth), 3.0);
}

// Bearing stamps scattered by 100 ms on precise bearings: the plain fit's sigmas under-cover
// (a parameter beyond 3σ), the timing-aware fit estimates σt within 3σ and every parameter
// within 3σ of the truth. (Over 12 seeds, DISABLED_JitterStudy: mean z² 13.7 plain, 1.33 aware.)
TEST(BearingTimingTest, StampJitterIsModelledAndTheSigmasCover) {
  BearingSimTruth truth;
  // Through the files, so that the reader's stamp diagnostics see the scatter.
  const fs::path dir =
      fs::temp_directory_path() / ("bearing_timing_test_" + std::to_string(getpid()));
  ASSERT_TRUE(WriteBearingLog(JitteredLog(JitterScene(1), 0.1, 1, &truth), dir.string()).ok());
  const StatusOr<BearingLog> read = ReadBearingLog(dir.string());
  fs::remove_all(dir);
  ASSERT_TRUE(read.ok()) << read.message();
  const BearingLog& log = *read;
  const StatusOr<BearingCalibrationResult> plain = CalibrateBearing(log, Plain());
  const StatusOr<BearingCalibrationResult> aware = CalibrateBearing(log);
  ASSERT_TRUE(plain.ok() && aware.ok());
  EXPECT_GT(WorstSigmas(*plain, truth), 3.0);
  EXPECT_TRUE(aware->timing.jitter_modelled) << aware->timing.statement;
  EXPECT_LE(std::abs(aware->timing.jitter.jitter_s - 0.1),
            3.0 * aware->timing.jitter.jitter_stddev_s);
  EXPECT_LE(WorstSigmas(*aware, truth), 3.0);
  EXPECT_GT(aware->noise.bearing_jitter_s, 0.0);
  // The bearing stream's stamps scatter about their grid: the output says they are not the
  // sample times.
  bool said = false;
  for (const std::string& w : aware->warnings) {
    said |= w.find("bearings stamps cannot be the sample times") != std::string::npos;
  }
  EXPECT_TRUE(said) << ::testing::PrintToString(aware->warnings);
}

// Encoder stamps scattered instead: the pose at a bearing time is interpolated from them, so the
// bearings see the same timing error; the jitter component takes it up.
TEST(BearingTimingTest, EncoderStampScatterShowsAsJitter) {
  BearingSimTruth truth;
  const BearingLog log = JitteredEncoderLog(JitterScene(2), 0.05, 2, &truth);
  const StatusOr<BearingCalibrationResult> aware = CalibrateBearing(log);
  ASSERT_TRUE(aware.ok()) << aware.message();
  EXPECT_TRUE(aware->timing.jitter_modelled) << aware->timing.statement;
  EXPECT_GT(aware->timing.jitter.jitter_s, 0.02);
  EXPECT_LE(WorstSigmas(*aware, truth), 3.0);
}

// z of the stamps-as-times ("plain") and timing-aware estimates over a study's seeds.
struct StudyTally {
  double plain_z2 = 0, aware_z2 = 0;
  int n = 0, plain_out = 0, aware_out = 0;
  void Add(const BearingCalibrationResult& plain, const BearingCalibrationResult& aware,
           const BearingSimTruth& truth) {
    const BearingParamVector t = ToVector(truth.params);
    for (int i = 0; i < kNumBearingParams; ++i) {
      const double zp = ParamError(i, ToVector(plain.estimate)(i), t(i)) / plain.stddev(i);
      const double za = ParamError(i, ToVector(aware.estimate)(i), t(i)) / aware.stddev(i);
      plain_z2 += zp * zp, aware_z2 += za * za, ++n;
      plain_out += std::abs(zp) > 2.0, aware_out += std::abs(za) > 2.0;
    }
  }
  void Print(const char* what, double value) const {
    std::printf("%s %.3f: mean z² plain %.2f aware %.2f; beyond 2σ plain %d aware %d of %d\n", what,
                value, plain_z2 / n, aware_z2 / n, plain_out, aware_out, n);
  }
};

TEST(BearingTimingTest, DISABLED_JitterStudy) {
  for (double jitter : {0.0, 0.05, 0.1}) {
    StudyTally tally;
    for (uint64_t seed = 1; seed <= 12; ++seed) {
      BearingSimTruth truth;
      const BearingLog log = JitteredLog(JitterScene(seed), jitter, seed, &truth);
      const StatusOr<BearingCalibrationResult> plain = CalibrateBearing(log, Plain());
      const StatusOr<BearingCalibrationResult> aware = CalibrateBearing(log);
      if (!plain.ok() || !aware.ok()) continue;
      tally.Add(*plain, *aware, truth);
      std::printf(
          "jitter %.3f seed %d: plain worst %.2f σ, aware worst %.2f σ (%s, σt %.4f ± %.4f, p "
          "%.2g)\n",
          jitter, static_cast<int>(seed), WorstSigmas(*plain, truth), WorstSigmas(*aware, truth),
          aware->timing.treatment.c_str(), aware->timing.jitter.jitter_s,
          aware->timing.jitter.jitter_stddev_s, aware->timing.jitter.p_value);
    }
    tally.Print("jitter", jitter);
  }
}

// A free-running bearing sensor (995 ms, drifting 2e-4) picked up by a logger every
// `logger_period_s` with 10 ms of jitter (core/timing/logging_model.h).
BearingSimOptions PickUpScene(uint64_t seed, double logger_period_s) {
  BearingSimOptions o = JitterScene(seed);
  o.logging.sensor_period_s = 0.995;
  o.logging.sensor_phase_s = 0.13;
  o.logging.sensor_clock_drift = 2e-4;
  o.logging.logger_period_s = logger_period_s;
  o.logging.logger_jitter_s = 0.01;
  return o;
}

// The logger outpaces the sensor (500 ms against 995 ms): every sample is picked up, most twice.
// Taking the stamps as sample times leaves a parameter > 3σ off; the calibration drops the
// repeats, puts each bearing on the sensor's clock (its period within 4σ of the truth) and every
// parameter within 3σ. (Over 12 seeds, DISABLED_PickUpStudy: mean z² 77 on the stamps, 3.2 on the
// clock, where the white-jitter model alone gave 4.2.)
TEST(BearingTimingTest, FreeRunningSensorIsPutOnItsClock) {
  BearingSimTruth truth;
  const BearingLog log = SimulateBearingLog(PickUpScene(2, 0.5), &truth);
  const StatusOr<BearingCalibrationResult> plain = CalibrateBearing(log, Plain());
  const StatusOr<BearingCalibrationResult> aware = CalibrateBearing(log);
  ASSERT_TRUE(plain.ok() && aware.ok()) << plain.message() << aware.message();
  EXPECT_GT(WorstSigmas(*plain, truth), 3.0);
  const BearingTiming& timing = aware->timing;
  EXPECT_TRUE(timing.clock_modelled) << timing.statement;
  EXPECT_EQ(timing.treatment.rfind("free-running sensor clock", 0), 0u) << timing.treatment;
  EXPECT_GT(timing.held_bearings_dropped, 100);
  const double true_period = 0.995 * (1.0 + 2e-4);
  EXPECT_LE(std::abs(timing.clock.period_s - true_period), 4.0 * timing.clock.period_stddev_s)
      << timing.clock.period_s << " ± " << timing.clock.period_stddev_s;
  EXPECT_LE(WorstSigmas(*aware, truth), 3.0);
}

// The logger is a little slower than the sensor (1 s against 995 ms): it misses a sample every
// ~200 s, which its stamps do not show, and the few samples it picks up twice near those beats
// show the free-running sensor. The log cannot fix the sensor's period, so the clock is not
// modelled and the result says that the timing may bias it.
TEST(BearingTimingTest, PeriodTheLogCannotFixIsAWarning) {
  BearingSimTruth truth;
  const BearingLog log = SimulateBearingLog(PickUpScene(2, 1.0), &truth);
  const StatusOr<BearingCalibrationResult> r = CalibrateBearing(log);
  ASSERT_TRUE(r.ok()) << r.message();
  EXPECT_FALSE(r->timing.clock_modelled);
  EXPECT_TRUE(r->timing.clock.free_running);
  EXPECT_FALSE(r->timing.clock.period_determined);
  bool said = false;
  for (const std::string& w : r->warnings) {
    said |= w.find("whose period the log cannot fix") != std::string::npos;
  }
  EXPECT_TRUE(said) << ::testing::PrintToString(r->warnings);
}

// A long run whose stamps are the sample times, each step's change 4σ clear of the noise so that
// the bearings count every step: noise alone makes some one-period steps read as two (about 44 of
// 20 000 here), which is not a free-running sensor. Genuinely missed samples, as many again on
// top, are.
TEST(BearingClockTest, NoiseAloneDoesNotMakeSkippedSamples) {
  constexpr int kSteps = 20000;
  const double sigma = 1.0 * kDeg, rate = 0.1;  // rad/s; one period's change 4.05 σ·√2.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, sigma);
  for (const int missed : {0, 90}) {
    BearingClockRun run;
    int sample = 0;
    for (int k = 0; k <= kSteps; ++k) {
      if (k > 0) sample += (missed > 0 && k % (kSteps / missed) == 0) ? 2 : 1;
      run.stamps_s.push_back(k);
      run.bearings_rad.push_back(WrapAngle(rate * sample + noise(rng)));
      run.rates_rad_per_s.push_back(rate);
      run.inlier.push_back(true);
    }
    const BearingClockEstimate clock = EstimateBearingClock({run}, sigma, 0);
    ASSERT_TRUE(clock.tested);
    if (missed == 0) {
      EXPECT_GE(clock.skipped_samples, 20);  // Noise's doing, ...
      EXPECT_FALSE(clock.free_running);      // ... and taken as such.
      EXPECT_FALSE(clock.period_determined);
    } else {
      EXPECT_GE(clock.skipped_samples, 90);
      EXPECT_TRUE(clock.free_running);
      EXPECT_TRUE(clock.period_determined);
    }
  }
}

TEST(BearingTimingTest, DISABLED_PickUpStudy) {
  for (double logger : {0.5, 1.0}) {
    StudyTally tally;
    for (uint64_t seed = 1; seed <= 12; ++seed) {
      BearingSimTruth truth;
      const BearingLog log = SimulateBearingLog(PickUpScene(seed, logger), &truth);
      const StatusOr<BearingCalibrationResult> plain = CalibrateBearing(log, Plain());
      BearingCalibrationOptions verbose;
      if (std::getenv("CALIB_VERBOSE")) {
        verbose.progress = [](const std::string& line) { std::printf("  %s\n", line.c_str()); };
      }
      const StatusOr<BearingCalibrationResult> aware = CalibrateBearing(log, verbose);
      if (!plain.ok() || !aware.ok()) {
        std::printf("seed %d failed: %s %s\n", static_cast<int>(seed), plain.message().c_str(),
                    aware.message().c_str());
        continue;
      }
      tally.Add(*plain, *aware, truth);
      std::printf(
          "logger %.2f seed %d: plain worst %.2f σ, aware worst %.2f σ (%s, τ %.4f ± %.4f, "
          "σt %.4f)\n",
          logger, static_cast<int>(seed), WorstSigmas(*plain, truth), WorstSigmas(*aware, truth),
          aware->timing.treatment.c_str(), aware->timing.time_offset_s,
          aware->timing.time_offset_stddev_s, aware->timing.jitter.jitter_s);
    }
    tally.Print("logger", logger);
  }
}

}  // namespace
}  // namespace calib
