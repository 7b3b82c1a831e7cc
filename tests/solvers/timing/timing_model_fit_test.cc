#include <calib/solvers/timing/clock_start.h>
#include <calib/solvers/timing/timing_model_fit.h>
#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace calib {
namespace {

constexpr double kPeriodS = 0.1;

// Sample times on a 100 ms grid with white scatter and a skipped sample every 97.
std::vector<double> ClockTimes(int count, double scatter_s, uint32_t seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, scatter_s);
  std::vector<double> times;
  for (int n = 0; static_cast<int>(times.size()) < count; ++n) {
    if (n % 97 != 96) times.push_back(0.013 + kPeriodS * n + noise(random));
  }
  return times;
}

// An irregular sampler: each step 100 ms ± up to 10 ms, the steps adding up.
std::vector<double> WanderingTimes(int count, uint32_t seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> step(kPeriodS - 0.01, kPeriodS + 0.01);
  std::vector<double> times = {0.0};
  while (static_cast<int>(times.size()) < count) times.push_back(times.back() + step(random));
  return times;
}

TimingModelFit StampFit(const std::vector<double>& times, double jitter_s) {
  TimingModelFit fit;
  fit.model = SensorClockModel::kStamps;
  fit.state.sensor_sigma_s = jitter_s;
  fit.sample_time_s = times;
  return fit;
}

StreamSamples Period() {
  StreamSamples data;
  data.sensor_period_s = kPeriodS;
  return data;
}

TEST(TimesStrayFromEveryClock, AClocksSamplesStayOnItsGrid) {
  EXPECT_FALSE(TimesStrayFromEveryClock(Period(), StampFit(ClockTimes(3000, 0.005, 1), 0.005)));
}

TEST(TimesStrayFromEveryClock, StepsThatAddUpStray) {
  // Over 2000 samples the steps' sum wanders by several periods from any grid.
  EXPECT_TRUE(TimesStrayFromEveryClock(Period(), StampFit(WanderingTimes(2000, 2), 0.002)));
}

TEST(TimesStrayFromEveryClock, NothingIsRuledOutWhereTheStampModelIsUnsure) {
  // A jitter of 30 % of the period: the stamp model's times may be pick-up times, not samples'.
  EXPECT_FALSE(TimesStrayFromEveryClock(Period(), StampFit(WanderingTimes(2000, 2), 0.03)));
  TimingModelFit clock = StampFit(WanderingTimes(2000, 2), 0.002);
  clock.model = SensorClockModel::kFreeRunning;
  EXPECT_FALSE(TimesStrayFromEveryClock(Period(), clock));
  EXPECT_FALSE(TimesStrayFromEveryClock(Period(), StampFit(WanderingTimes(20, 2), 0.002)));
}

TEST(StartingJitter, ScatterAboutAGridCountsStepsThatAddUpDoNot) {
  const double white = StartingJitter(ClockTimes(3000, 0.005, 3), kPeriodS);
  EXPECT_NEAR(white, 2.0 * 0.005, 0.3 * 2.0 * 0.005);
  // The irregular sampler's stamps are its sample times: the search starts at its floor.
  EXPECT_LT(StartingJitter(WanderingTimes(3000, 4), kPeriodS), 0.002);
}

}  // namespace
}  // namespace calib
