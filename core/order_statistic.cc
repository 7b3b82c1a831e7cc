#include <calib/core/order_statistic.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>

namespace calib {
namespace {

// Below this many values nth_element is as fast as the bracket.
constexpr size_t kBracketAbove = 1024;
constexpr size_t kMinSample = 256;
constexpr size_t kMaxSample = 4096;

double Fallback(std::vector<double>* values, size_t k) {
  std::nth_element(values->begin(), values->begin() + static_cast<long>(k), values->end());
  return (*values)[k];
}

}  // namespace

double KthSmallest(std::vector<double>* values, size_t k) {
  std::vector<double>& v = *values;
  const size_t n = v.size();
  if (n < kBracketAbove) return Fallback(values, k);
  // An evenly spread sample of s values: the k-th value's rank in it has a standard deviation of
  // at most √(s/4), and a bracket of 5 of those either side misses about once in a million.
  const size_t s = std::clamp(n / 8, kMinSample, kMaxSample);
  const long half_width = static_cast<long>(std::ceil(5.0 * std::sqrt(0.25 * s)));
  std::vector<double> sample(s);
  for (size_t i = 0; i < s; ++i) sample[i] = v[i * (n / s)];
  if (!std::all_of(sample.begin(), sample.end(), [](double x) { return !std::isnan(x); })) {
    return Fallback(values, k);
  }
  const long at = static_cast<long>(static_cast<double>(k) / static_cast<double>(n) * s);
  const long low_rank = at - half_width, high_rank = at + half_width;
  const bool bounded_below = low_rank >= 0, bounded_above = high_rank < static_cast<long>(s);
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  if (bounded_below) {
    std::nth_element(sample.begin(), sample.begin() + low_rank, sample.end());
    lo = sample[low_rank];
  }
  if (bounded_above) {
    const auto from = bounded_below ? sample.begin() + low_rank : sample.begin();
    std::nth_element(from, sample.begin() + high_rank, sample.end());
    hi = sample[high_rank];
  }
  // One pass without branches on the values: count those below, gather those inside.
  const std::unique_ptr<double[]> inside(new double[n]);
  size_t below = 0, above = 0, m = 0;
  for (const double x : v) {
    below += x < lo;
    above += x > hi;
    inside[m] = x;
    m += (x >= lo) & (x <= hi);
  }
  // A NaN falls in none of the three: the counts then do not add up.
  if (below + m + above != n || k < below || k >= below + m) return Fallback(values, k);
  const size_t j = k - below;
  std::nth_element(inside.get(), inside.get() + j, inside.get() + m);
  return inside[j];
}

double UpperMedian(std::vector<double>* values) {
  return values->empty() ? 0.0 : KthSmallest(values, values->size() / 2);
}

namespace {

// The key whose unsigned order is the values' order: −0 as +0, negatives' bits inverted, NaN
// last.
uint64_t OrderedKey(double value) {
  if (std::isnan(value)) return ~uint64_t{0};
  value += 0.0;  // −0 → +0.
  uint64_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  constexpr uint64_t kSign = uint64_t{1} << 63;
  return bits & kSign ? ~bits : bits | kSign;
}

// LSD radix sort of the keys in digits of `kBits` bits, carrying the indices along; every pass's
// histogram from one read of the keys.
template <int kBits>
std::vector<size_t> RadixOrder(const std::vector<double>& values) {
  const size_t n = values.size();
  std::vector<size_t> order(n);
  for (size_t k = 0; k < n; ++k) order[k] = k;
  if (n < 2) return order;
  constexpr int kPasses = (64 + kBits - 1) / kBits;
  constexpr size_t kBuckets = size_t{1} << kBits;
  std::vector<uint64_t> keys(n), keys_next(n);
  std::vector<size_t> order_next(n);
  std::vector<size_t> counts(kPasses * kBuckets, 0);
  for (size_t k = 0; k < n; ++k) {
    keys[k] = OrderedKey(values[k]);
    for (int pass = 0; pass < kPasses; ++pass) {
      ++counts[pass * kBuckets + ((keys[k] >> (pass * kBits)) & (kBuckets - 1))];
    }
  }
  for (int pass = 0; pass < kPasses; ++pass) {
    size_t* count = counts.data() + pass * kBuckets;
    const int shift = pass * kBits;
    // A digit every key shares leaves the order as it is.
    if (count[(keys[0] >> shift) & (kBuckets - 1)] == n) continue;
    size_t start = 0;
    for (size_t b = 0; b < kBuckets; ++b) {
      const size_t c = count[b];
      count[b] = start;
      start += c;
    }
    for (size_t i = 0; i < n; ++i) {
      const size_t to = count[(keys[i] >> shift) & (kBuckets - 1)]++;
      keys_next[to] = keys[i];
      order_next[to] = order[i];
    }
    keys.swap(keys_next);
    order.swap(order_next);
  }
  return order;
}

// Below this many values the histograms of 11-bit digits (six of 2048 counts, 96 kB) no longer fit
// the first-level cache beside the keys, and eight passes of 8-bit digits are faster (a
// real set's few thousand intervals: a third less time).
constexpr size_t kWideDigitsFrom = size_t{1} << 16;

}  // namespace

std::vector<size_t> StableOrder(const std::vector<double>& values) {
  return values.size() < kWideDigitsFrom ? RadixOrder<8>(values) : RadixOrder<11>(values);
}

}  // namespace calib
