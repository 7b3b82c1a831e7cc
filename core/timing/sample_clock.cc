#include <calib/core/timing/sample_clock.h>

#include <algorithm>
#include <cmath>

namespace calib {

std::vector<double> ClockIndicesFromStamps(const std::vector<double>& stamps_s,
                                           const SampleClock& clock) {
  std::vector<double> n(stamps_s.size(), 0.0);
  for (size_t k = 0; k < n.size(); ++k) {
    // Invert t(n) = s by a fixed point on the drift term (a ≪ P·n makes it converge at once).
    double index = (stamps_s[k] - clock.t0_s) / clock.period_s;
    for (int i = 0; i < 3; ++i) {
      index = (stamps_s[k] - clock.t0_s - clock.drift_s * clock.Curvature(index)) / clock.period_s;
    }
    n[k] = std::floor(index);
    if (k > 0) n[k] = std::max(n[k], n[k - 1] + 1.0);
  }
  return n;
}

SampleClock FitSampleClock(const std::vector<double>& indices, const std::vector<double>& times_s) {
  SampleClock clock;
  const size_t count = std::min(indices.size(), times_s.size());
  if (count < 2) return clock;
  double mean_n = 0.0, mean_t = 0.0;
  for (size_t k = 0; k < count; ++k) {
    mean_n += indices[k] / count;
    mean_t += times_s[k] / count;
  }
  double snn = 0.0, snt = 0.0;
  for (size_t k = 0; k < count; ++k) {
    snn += (indices[k] - mean_n) * (indices[k] - mean_n);
    snt += (indices[k] - mean_n) * (times_s[k] - mean_t);
  }
  clock.period_s = snt / snn;
  clock.t0_s = mean_t - clock.period_s * mean_n;
  clock.index_mid = 0.5 * (indices.front() + indices[count - 1]);
  clock.index_half = std::max(1.0, 0.5 * (indices[count - 1] - indices.front()));
  return clock;
}

double MedianStep(const std::vector<double>& values) {
  std::vector<double> steps;
  for (size_t k = 1; k < values.size(); ++k) {
    if (values[k] > values[k - 1]) steps.push_back(values[k] - values[k - 1]);
  }
  if (steps.empty()) return 0.0;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2];
}

}  // namespace calib
