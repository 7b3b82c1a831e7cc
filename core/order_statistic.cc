#include <calib/core/order_statistic.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace calib {
namespace {

// Below this many values nth_element is as fast as the bracket.
constexpr size_t kBracketAbove = size_t{1} << 16;
constexpr size_t kSample = 4096;
// Half-width of the bracket in sample ranks: the k-th value's rank in the sample has a standard
// deviation of at most √(4096/4) = 32, so 160 ranks miss once in millions.
constexpr size_t kHalfWidth = 160;

double Fallback(std::vector<double>* values, size_t k) {
  std::nth_element(values->begin(), values->begin() + static_cast<long>(k), values->end());
  return (*values)[k];
}

}  // namespace

double KthSmallest(std::vector<double>* values, size_t k) {
  std::vector<double>& v = *values;
  const size_t n = v.size();
  if (n < kBracketAbove) return Fallback(values, k);
  std::vector<double> sample(kSample);
  for (size_t i = 0; i < kSample; ++i) sample[i] = v[i * (n / kSample)];
  if (!std::all_of(sample.begin(), sample.end(), [](double x) { return !std::isnan(x); })) {
    return Fallback(values, k);
  }
  std::sort(sample.begin(), sample.end());
  const size_t at = static_cast<size_t>(static_cast<double>(k) / static_cast<double>(n) * kSample);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double lo = at >= kHalfWidth ? sample[at - kHalfWidth] : -kInf;
  const double hi = at + kHalfWidth < kSample ? sample[at + kHalfWidth] : kInf;
  size_t below = 0, above = 0;
  std::vector<double> inside;
  inside.reserve(n / kSample * (2 * kHalfWidth + 1) * 2);
  for (const double x : v) {
    if (x < lo) {
      ++below;
    } else if (x <= hi) {
      inside.push_back(x);
    } else if (x > hi) {
      ++above;
    }
  }
  // A NaN falls in none of the three: the counts then do not add up.
  if (below + inside.size() + above != n || k < below || k >= below + inside.size()) {
    return Fallback(values, k);
  }
  const size_t j = k - below;
  std::nth_element(inside.begin(), inside.begin() + static_cast<long>(j), inside.end());
  return inside[j];
}

double UpperMedian(std::vector<double>* values) {
  return values->empty() ? 0.0 : KthSmallest(values, values->size() / 2);
}

}  // namespace calib
