#include <calib/core/encoder_spikes.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace calib {
namespace {

constexpr double kAbsurdValue = 1e9;
constexpr double kScaleFactor = 1000.0;

// The (m+1)-th largest |step| of one wheel, or 0 when there are too few steps.
double StepScale(const std::vector<double>& steps, size_t m) {
  if (steps.size() <= m) return 0.0;
  std::vector<double> a(steps.size());
  for (size_t i = 0; i < steps.size(); ++i) a[i] = std::abs(steps[i]);
  std::nth_element(a.begin(), a.end() - 1 - static_cast<long>(m), a.end());
  return *(a.end() - 1 - static_cast<long>(m));
}

}  // namespace

std::vector<bool> FindEncoderSpikes(const std::vector<EncoderSample>& samples) {
  const size_t n = samples.size();
  std::vector<bool> spike(n, false);
  for (size_t k = 0; k < n; ++k) {
    // Not NaN or infinity: those are the reader's to refuse, naming the line.
    const double largest = std::max(std::abs(samples[k].left_rad), std::abs(samples[k].right_rad));
    spike[k] = std::isfinite(largest) && largest > kAbsurdValue;
  }
  if (n >= 3) {
    const size_t m = std::max<size_t>(4, n / 25);
    for (int wheel = 0; wheel < 2; ++wheel) {
      const auto value = [&](size_t k) {
        return wheel == 0 ? samples[k].left_rad : samples[k].right_rad;
      };
      std::vector<double> steps;
      for (size_t k = 1; k < n; ++k) {
        const double step = value(k) - value(k - 1);
        if (!spike[k] && !spike[k - 1] && std::isfinite(step)) steps.push_back(step);
      }
      const double limit = kScaleFactor * StepScale(steps, m);
      if (!(limit > 0.0)) continue;
      for (size_t k = 1; k + 1 < n; ++k) {
        const double in = value(k) - value(k - 1), out = value(k + 1) - value(k);
        if (std::abs(in) > limit && std::abs(out) > limit && (in > 0) != (out > 0)) spike[k] = true;
      }
    }
  }
  const size_t count = static_cast<size_t>(std::count(spike.begin(), spike.end(), true));
  if (count > std::max<size_t>(2, n / 50)) return std::vector<bool>(n, false);
  return spike;
}

int DropEncoderSpikes(std::vector<EncoderSample>* samples, int* first_line) {
  const std::vector<bool> spike = FindEncoderSpikes(*samples);
  std::vector<EncoderSample> kept;
  kept.reserve(samples->size());
  int dropped = 0;
  for (size_t k = 0; k < samples->size(); ++k) {
    if (!spike[k]) {
      kept.push_back((*samples)[k]);
    } else if (dropped++ == 0 && first_line != nullptr) {
      *first_line = (*samples)[k].line;
    }
  }
  *samples = std::move(kept);
  return dropped;
}

}  // namespace calib
