#include <calib/core/se2.h>
#include <calib/core/timing/encoder_integration.h>
#include <calib/solvers/timing/clock_indices.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace calib {
namespace {

constexpr int kOffsets = 3;               // −1, 0, +1.
constexpr double kWindowScale = 0.02;     // Of the period: the lag penalty's unit.
constexpr double kMotionLossScale = 3.0;  // Cauchy scale of the whitened motion misfit.

double Cauchy(double squared) {
  const double c2 = kMotionLossScale * kMotionLossScale;
  return c2 * std::log1p(squared / c2);
}

// The encoders at their latent times when the state has them.
std::vector<EncoderSample> TimedEncoders(const StreamSamples& data, const LatentTimeState& s) {
  std::vector<EncoderSample> encoders = data.encoders;
  if (s.encoder_latent.size() == encoders.size()) {
    for (size_t j = 0; j < encoders.size(); ++j) encoders[j].t_s += s.encoder_latent[j];
    std::stable_sort(encoders.begin(), encoders.end(),
                     [](const EncoderSample& a, const EncoderSample& b) { return a.t_s < b.t_s; });
  }
  return encoders;
}

}  // namespace

std::vector<double> ReassignClockIndices(const StreamSamples& data, const LatentTimeState& s) {
  const size_t n = data.samples.size();
  std::vector<double> lags, stamps;
  for (size_t k = 0; k < n; ++k) {
    stamps.push_back(data.samples[k].stamp_s);
    lags.push_back(stamps.back() - s.clock.Time(s.clock_index[k]));
  }
  std::vector<double> sorted = lags;
  const size_t q = sorted.size() / 50;
  std::nth_element(sorted.begin(), sorted.begin() + q, sorted.end());
  const double delay = sorted[q] - 0.02 * s.clock.period_s;
  SampleClock shifted = s.clock;
  shifted.t0_s += delay;
  const std::vector<double> base = ClockIndicesFromStamps(stamps, shifted);
  if (n < 2 || !(s.clock.period_s > 0.0)) return base;

  const std::vector<EncoderSample> encoders = TimedEncoders(data, s);
  const LaserParamVector v = s.calibration.ToVector();
  const Pose2d mounting(v(3), v(4), v(5));
  const Eigen::Vector3d inverse_sigma = s.noise_sigma.cwiseInverse();
  const double unit = kWindowScale * s.clock.period_s;
  // Per sample and offset: the index, its wheel angles and its lag penalty.
  struct Candidate {
    double index = 0.0, left = 0.0, right = 0.0, penalty = 0.0;
  };
  std::vector<std::array<Candidate, kOffsets>> candidates(n);
  for (size_t k = 0; k < n; ++k) {
    for (int o = 0; o < kOffsets; ++o) {
      Candidate& c = candidates[k][o];
      c.index = base[k] + o - 1;
      const double t = s.clock.Time(c.index);
      InterpolateWheelAngles(encoders, t, &c.left, &c.right);
      const double lag = stamps[k] - t - delay;  // In [0, P) inside the window.
      const double outside = lag < 0.0 ? -lag : std::max(0.0, lag - s.clock.period_s);
      c.penalty = (outside / unit) * (outside / unit);
    }
  }
  const double kInfinity = std::numeric_limits<double>::infinity();
  std::vector<std::array<double, kOffsets>> cost(n);
  std::vector<std::array<int, kOffsets>> from(n);
  for (int o = 0; o < kOffsets; ++o) cost[0][o] = candidates[0][o].penalty;
  for (size_t k = 1; k < n; ++k) {
    Eigen::Vector3d measured =
        Between(data.samples[k - 1].world_T_sensor, data.samples[k].world_T_sensor);
    measured(2) = WrapAngle(measured(2));
    for (int o = 0; o < kOffsets; ++o) {
      const Candidate& end = candidates[k][o];
      cost[k][o] = kInfinity;
      from[k][o] = 1;
      for (int p = 0; p < kOffsets; ++p) {
        const Candidate& start = candidates[k - 1][p];
        if (!(end.index > start.index) || !std::isfinite(cost[k - 1][p])) continue;
        const double left[2] = {start.left, end.left}, right[2] = {start.right, end.right};
        const Pose2d robot = WheelAngleChainDisplacement(v(0), v(1), v(2), left, right, 2);
        Eigen::Vector3d misfit = measured - SensorMotionFromRobotMotion(mounting, robot);
        misfit(2) = WrapAngle(misfit(2));
        const double total =
            cost[k - 1][p] + end.penalty + Cauchy(misfit.cwiseProduct(inverse_sigma).squaredNorm());
        if (total < cost[k][o]) cost[k][o] = total, from[k][o] = p;
      }
    }
  }
  std::vector<double> indices(n);
  int o = static_cast<int>(std::min_element(cost[n - 1].begin(), cost[n - 1].end()) -
                           cost[n - 1].begin());
  if (!std::isfinite(cost[n - 1][o])) return base;
  for (size_t k = n; k-- > 0;) {
    indices[k] = candidates[k][o].index;
    if (k > 0) o = from[k][o];
  }
  return indices;
}

}  // namespace calib
