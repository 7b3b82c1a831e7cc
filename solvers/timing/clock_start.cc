#include <calib/core/se2.h>
#include <calib/core/timing/encoder_integration.h>
#include <calib/core/timing/sample_clock.h>
#include <calib/solvers/timing/clock_indices.h>
#include <calib/solvers/timing/clock_start.h>
#include <calib/solvers/timing/pick_up_clock.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace calib {
namespace {

// Per interval k (samples k − 1 and k): the stamp step in periods, the wheels' motion between the
// two stamps (as sensor motion), and the measured motion over it, trusted where the motion is
// known to 5 % and the measured motion is a multiple of the predicted one in every component (not
// a failed scan match). A sample the logger skipped doubles the ratio.
struct IntervalMotion {
  std::vector<double> stamp_ratio, motion_ratio;
  std::vector<bool> trusted;
  std::vector<Eigen::Vector3d> wheel_motion;
};

IntervalMotion MeasureIntervalMotion(const StreamSamples& data, const LatentTimeState& s,
                                     const Eigen::Vector3d& weight) {
  const size_t n = data.samples.size();
  IntervalMotion m;
  m.stamp_ratio.assign(n, 0.0);
  m.motion_ratio.assign(n, 1.0);
  m.trusted.assign(n, false);
  m.wheel_motion.assign(n, Eigen::Vector3d::Zero());
  const LaserParamVector v = s.calibration.ToVector();
  const Pose2d mounting(v(3), v(4), v(5));
  for (size_t k = 1; k < n; ++k) {
    m.stamp_ratio[k] =
        (data.samples[k].stamp_s - data.samples[k - 1].stamp_s) / data.sensor_period_s;
    double left[2], right[2];
    for (int i = 0; i < 2; ++i) {
      InterpolateWheelAngles(data.encoders, data.samples[k - 1 + i].stamp_s, &left[i], &right[i]);
    }
    const Pose2d robot = WheelAngleChainDisplacement(v(0), v(1), v(2), left, right, 2);
    const Eigen::Vector3d predicted = SensorMotionFromRobotMotion(mounting, robot);
    m.wheel_motion[k] = predicted;
    Eigen::Vector3d measured =
        Between(data.samples[k - 1].world_T_sensor, data.samples[k].world_T_sensor);
    measured(2) = WrapAngle(measured(2));
    const double information = predicted.dot(weight.cwiseProduct(predicted));
    const double scale = measured.dot(weight.cwiseProduct(predicted)) / information;
    const Eigen::Vector3d misfit = measured - scale * predicted;
    m.trusted[k] = information > 400.0 && misfit.dot(weight.cwiseProduct(misfit)) < 16.0;
    if (m.trusted[k]) m.motion_ratio[k] = scale;
  }
  return m;
}

// Trusted intervals whose wheel motion per stamp step matches both neighbours' to 10 %: a pick-up
// stamp lags its sample by up to a period, so elsewhere (the robot speeding up from rest) the
// measured motion can be twice the wheels' between the stamps without a skipped sample.
std::vector<bool> Steady(const std::vector<bool>& trusted,
                         const std::vector<Eigen::Vector3d>& wheel_motion,
                         const Eigen::Vector3d& weight) {
  std::vector<bool> steady(trusted.size(), false);
  const auto norm = [&](const Eigen::Vector3d& v) {
    return std::sqrt(v.dot(weight.cwiseProduct(v)));
  };
  for (size_t k = 2; k + 1 < trusted.size(); ++k) {
    const double size = norm(wheel_motion[k]);
    steady[k] = trusted[k] && norm(wheel_motion[k] - wheel_motion[k - 1]) < 0.1 * size &&
                norm(wheel_motion[k] - wheel_motion[k + 1]) < 0.1 * size;
  }
  return steady;
}

// Where whole numbers hold most counts, the logger may still pick up every m-th sample of a sensor
// m times as fast (a 100 ms lidar read every 200 ms): its jitter then crosses a sample now and
// then, and those steps count m ± 1 of its periods, 0.5 and 1.5 stamp steps for m = 2 (a fifth
// of the steps on a simulated log, whose sample times the stamp model had put 37 ms off). The
// unit is 1/m when the counts clearly off whole numbers (a quarter or more) are at least 5 and
// 3 %, and 80 % of them sit on multiples of 1/m; else 1.
template <typename Refine>
double WholeOrFraction(const std::vector<double>& counted, const Refine& refined) {
  std::vector<double> off;
  for (const double c : counted) {
    if (std::abs(c - std::round(c)) >= 0.25) off.push_back(c);
  }
  if (off.size() < 5 || off.size() < 0.03 * counted.size()) return 1.0;
  for (const int m : {2, 3, 4}) {
    const auto on = std::count_if(off.begin(), off.end(), [&](double c) {
      return std::abs(c * m - std::round(c * m)) < 0.1;
    });
    if (on >= 0.8 * off.size()) return refined(1.0 / m);
  }
  return 1.0;
}

// The sensor's period in stamp steps as the motion counts it (stamp step × measured over wheel
// motion, `steady` intervals): 1 where the counts sit near whole numbers. A logger slower than its
// free-running sensor holds one or two periods per stamp step, so its counts sit near multiples of
// P/step instead (0.77 and 1.54 for a 100 ms sensor picked up every 130 ms) and its stamps' median
// step is not the period: the largest unit in [0.5, 0.9] whose multiples hold 90 % of the counts
// (within a tenth of the unit), refined as their median per multiple, where whole numbers hold
// under half of them; where they hold more, WholeOrFraction.
double MotionUnit(const std::vector<double>& stamp_ratio, const std::vector<double>& motion_ratio,
                  const std::vector<bool>& steady) {
  std::vector<double> counted;
  for (size_t k = 1; k < steady.size() && counted.size() < 2000; ++k) {
    if (steady[k]) counted.push_back(stamp_ratio[k] * motion_ratio[k]);
  }
  if (counted.size() < 20) return 1.0;
  const auto held = [&](double unit) {
    int near = 0;
    for (const double c : counted) {
      const double m = std::round(c / unit);
      near += m >= 1.0 && std::abs(c / unit - m) < 0.1;
    }
    return static_cast<double>(near) / counted.size();
  };
  const auto refined = [&](double unit) {
    std::vector<double> units;
    for (const double c : counted) {
      const double m = std::round(c / unit);
      if (m >= 1.0 && std::abs(c / unit - m) < 0.1) units.push_back(c / m);
    }
    std::nth_element(units.begin(), units.begin() + units.size() / 2, units.end());
    return units[units.size() / 2];
  };
  if (held(1.0) >= 0.5) return WholeOrFraction(counted, refined);
  for (double unit = 0.9; unit >= 0.5; unit -= 0.001) {
    if (held(unit) >= 0.9) return refined(unit);
  }
  return 1.0;
}

// Whole sensor periods (of `unit` stamp steps) per interval as the motion counts them, where it
// is trusted and within a quarter of a whole number; else 0.
std::vector<int> MotionPeriods(const std::vector<double>& stamp_ratio,
                               const std::vector<double>& motion_ratio,
                               const std::vector<bool>& trusted, double unit) {
  std::vector<int> periods(stamp_ratio.size(), 0);
  for (size_t k = 1; k < periods.size(); ++k) {
    const double counted = stamp_ratio[k] * motion_ratio[k] / unit;
    if (trusted[k] && counted > 0.75 && std::abs(counted - std::round(counted)) < 0.25) {
      periods[k] = static_cast<int>(std::round(counted));
    }
  }
  return periods;
}

// Whether `times`, counting whole periods between neighbours, stray from the best regular grid by
// more than `spread_periods` periods (the spread of their central 98 %): steps that vary and add
// up, as an irregular sampler's do, however small each step's variation.
bool StrayFromEveryClock(const std::vector<double>& times, double period, double spread_periods) {
  if (times.size() < 50 || !(period > 0.0)) return false;
  std::vector<double> indices = {0.0};
  for (size_t k = 1; k < times.size(); ++k) {
    indices.push_back(indices.back() +
                      std::max(1.0, std::round((times[k] - times[k - 1]) / period)));
  }
  const SampleClock clock = FitSampleClock(indices, times);
  std::vector<double> residual;
  for (size_t k = 0; k < times.size(); ++k) residual.push_back(times[k] - clock.Time(indices[k]));
  const size_t low = residual.size() / 100, high = residual.size() - 1 - low;
  std::nth_element(residual.begin(), residual.begin() + low, residual.end());
  const double q_low = residual[low];
  std::nth_element(residual.begin(), residual.begin() + high, residual.end());
  return residual[high] - q_low > spread_periods * period;
}

// Stamps on a grid of the period (steps within 5 % of whole periods), that never repeat a
// sample (a logger's pick-up does when its loop outruns the sensor) and whose steps the motion
// confirms (a logger slower than the sensor skips samples: double motion in one stamp step) are
// the sample times up to a small scatter. Their steps count the periods; the motion ratio of a
// single interval (wheel angles interpolated between polls while the robot accelerates) would
// only add errors. A logger slower than its sensor skips one sample in hundreds, too few for the
// 5 % of disagreeing intervals, so the clear skips the motion counts are looked at too. And steps
// near whole periods that add up (an irregular sampler's) stray from every grid.
bool StampsCountPeriods(const StreamSamples& data, const IntervalMotion& m,
                        const std::vector<int>& motion_periods) {
  std::vector<double> off_grid;
  int trusted_count = 0, disagreeing = 0, skips = 0;
  for (size_t k = 1; k < m.stamp_ratio.size(); ++k) {
    off_grid.push_back(std::abs(m.stamp_ratio[k] - std::round(m.stamp_ratio[k])));
    trusted_count += m.trusted[k];
    // 1.5 % on exact stamps.
    disagreeing += m.trusted[k] && std::abs(m.motion_ratio[k] - 1.0) > 0.15;
    skips += motion_periods[k] > std::round(m.stamp_ratio[k]);
  }
  if (off_grid.empty() || data.held_repeats_dropped > 0 || disagreeing > 0.05 * trusted_count ||
      skips >= std::max(3.0, 0.001 * trusted_count)) {
    return false;
  }
  std::nth_element(off_grid.begin(), off_grid.begin() + off_grid.size() / 2, off_grid.end());
  if (!(1.4826 * off_grid[off_grid.size() / 2] < 0.05)) return false;
  // Steps near whole periods do not make a clock when their variations add up: an irregular
  // sampler's stamps wander from every grid. They name a clock's samples only within half a
  // period of its grid (5 % steps from white scatter stay within about a sixth).
  std::vector<double> stamps;
  for (const StreamSample& sample : data.samples) stamps.push_back(sample.stamp_s);
  return !StrayFromEveryClock(stamps, data.sensor_period_s, 0.5);
}

// The clock that names every sample from pick-up stamps: held repeats first, else skips the
// motion counted (MotionPeriods, steady stretches only). Named indices are never re-assigned
// (re-assigning them by the motion had drifted P to the logger's period on 10⁴-scan logs); a
// wrong P they might name still has to beat the stamp model's evidence.
std::optional<PickUpClock> PickUpClockOf(const StreamSamples& data,
                                         const std::optional<PickUpClock>& pick_up_known,
                                         const std::vector<int>& motion_periods, double period_s) {
  std::optional<PickUpClock> pick_up = pick_up_known ? pick_up_known : FitPickUpClock(data);
  if (!pick_up || !pick_up->NamesEverySample()) {
    if (std::optional<PickUpClock> counted = FitPickUpClock(data, motion_periods, period_s)) {
      pick_up = std::move(counted);
    }
  }
  return pick_up;
}

// Per-interval motion, the periods it counts over steady stretches, and the grid test on them.
struct PeriodCount {
  IntervalMotion motion;
  std::vector<int> motion_periods;
  double unit = 1.0;  // MotionUnit.
  bool stamps_count = false;
};

PeriodCount CountPeriods(const StreamSamples& data, const LatentTimeState& s) {
  PeriodCount c;
  const Eigen::Vector3d weight = s.noise_sigma.cwiseInverse().cwiseAbs2();
  c.motion = MeasureIntervalMotion(data, s, weight);
  const std::vector<bool> steady = Steady(c.motion.trusted, c.motion.wheel_motion, weight);
  c.unit = MotionUnit(c.motion.stamp_ratio, c.motion.motion_ratio, steady);
  c.motion_periods = MotionPeriods(c.motion.stamp_ratio, c.motion.motion_ratio, steady, c.unit);
  c.stamps_count = StampsCountPeriods(data, c.motion, c.motion_periods);
  return c;
}

}  // namespace

bool StampsCountSensorPeriods(const StreamSamples& data, const LatentTimeState& state) {
  return data.samples.size() >= 2 && CountPeriods(data, state).stamps_count;
}

std::optional<PickUpClock> MotionCountedPickUpClock(const StreamSamples& data,
                                                    const LatentTimeState& state) {
  if (data.samples.size() < 2) return std::nullopt;
  const PeriodCount count = CountPeriods(data, state);
  if (count.stamps_count) return std::nullopt;
  std::optional<PickUpClock> clock =
      FitPickUpClock(data, count.motion_periods, count.unit * data.sensor_period_s);
  if (clock && !clock->NamesEverySample()) return std::nullopt;
  return clock;
}

bool TimesStrayFromEveryClock(const StreamSamples& data, const TimingModelFit& stamps) {
  if (stamps.model != SensorClockModel::kStamps ||
      !(stamps.state.sensor_sigma_s < 0.1 * data.sensor_period_s)) {
    return false;
  }
  return StrayFromEveryClock(stamps.sample_time_s, data.sensor_period_s, 1.0);
}

LatentTimeState ClockStartFromTimes(const StreamSamples& data, const TimingModelFit& stamps,
                                    const std::optional<PickUpClock>& pick_up_known) {
  LatentTimeState s = stamps.state;
  // Whole sensor periods per interval: where the robot moves, the ratio of the measured motion to
  // the motion the wheels made between the two stamps; elsewhere the stamp step. The clock is then
  // fitted to the stamps and the indices re-assigned.
  const PeriodCount count = CountPeriods(data, s);
  const IntervalMotion& m = count.motion;
  const std::vector<int>& motion_periods = count.motion_periods;
  // A clock that names every sample given by the caller outranks the grid test here: at the
  // stamp model's state the motion may confirm nothing (its noise took the skips in), and stamps
  // that no motion contradicts then pass for a grid of the period.
  const bool on_grid = count.stamps_count && !(pick_up_known && pick_up_known->NamesEverySample());
  const size_t n = data.samples.size();
  std::vector<double> steps(n, 0.0);
  for (size_t k = 1; k < n; ++k) {
    const double ratio = on_grid ? m.stamp_ratio[k] : m.stamp_ratio[k] * m.motion_ratio[k];
    steps[k] = std::max(1.0, std::round(ratio));
  }
  // Pick-up stamps name their samples exactly once the period is known: the motion ratios alone
  // miss skips where the robot stands still or the match is poor.
  s.clock_indices_named = false;
  s.period_prior_s = s.period_prior_sigma_s = 0.0;
  if (!on_grid) {
    if (const std::optional<PickUpClock> pick_up =
            PickUpClockOf(data, pick_up_known, motion_periods, count.unit * data.sensor_period_s)) {
      for (size_t k = 1; k < n; ++k) steps[k] = pick_up->indices[k] - pick_up->indices[k - 1];
      s.clock_indices_named = pick_up->NamesEverySample();
      if (s.clock_indices_named) {
        s.period_prior_s = pick_up->period_s;
        s.period_prior_sigma_s = std::max(pick_up->period_stddev_s, 1e-9);
      }
    }
  }
  s.clock_index.assign(data.samples.size(), 0.0);
  std::vector<double> stamps_s = {data.samples.front().stamp_s};
  for (size_t k = 1; k < data.samples.size(); ++k) {
    s.clock_index[k] = s.clock_index[k - 1] + steps[k];
    stamps_s.push_back(data.samples[k].stamp_s);
  }
  s.clock = FitSampleClock(s.clock_index, stamps_s);
  for (int round = 0; round < 2 && !s.clock_indices_named; ++round) {
    s.clock_index = ReassignClockIndices(data, s);
    s.clock = FitSampleClock(s.clock_index, stamps_s);
  }
  // The stamp prior starts at the scatter of the stamps about the fitted clock.
  double mean = 0.0, square = 0.0;
  for (size_t k = 0; k < stamps_s.size(); ++k) {
    const double lag = s.clock.Time(s.clock_index[k]) - stamps_s[k];
    mean += lag / stamps_s.size();
    square += lag * lag / stamps_s.size();
  }
  // Only stamps on the grid pin the clock: pick-up stamps name their sample only up to the
  // skips, and a prior on them would hold the clock to a miscounted set of indices.
  s.offset_s = mean;
  s.sensor_sigma_s =
      on_grid ? std::max(kJitterFloor, std::sqrt(std::max(0.0, square - mean * mean))) : 0.0;
  s.bracket.clear();
  return s;
}

}  // namespace calib
