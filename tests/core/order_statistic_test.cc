#include <calib/core/order_statistic.h>
#include <calib/core/random.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace calib {
namespace {

double NthElement(std::vector<double> v, size_t k) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

// Equal to nth_element's value for every kind of array: short and long, heavy tails, many ties,
// sorted either way, and k at the ends and in between.
TEST(OrderStatisticTest, KthSmallestEqualsNthElement) {
  Random random(11);
  for (const size_t n : {size_t{1}, size_t{7}, size_t{1000}, size_t{1024}, size_t{4345},
                         size_t{20000}, size_t{70000}, size_t{300001}}) {
    std::vector<std::vector<double>> arrays(5, std::vector<double>(n));
    for (size_t i = 0; i < n; ++i) {
      arrays[0][i] = random.Normal();
      arrays[1][i] = random.Normal() / std::max(1e-3, std::abs(random.Normal()));  // Cauchy.
      arrays[2][i] = std::floor(random.Uniform(0.0, 5.0));  // Five values, many ties.
      arrays[3][i] = static_cast<double>(i);
      arrays[4][i] = -static_cast<double>(i);
    }
    for (const std::vector<double>& array : arrays) {
      for (const size_t k : {size_t{0}, n / 5, n / 2, n - n / 7 - 1, n - 1}) {
        std::vector<double> copy = array;
        EXPECT_EQ(KthSmallest(&copy, k), NthElement(array, k)) << "n " << n << ", k " << k;
      }
    }
  }
}

// A NaN among the values takes the fallback and does not crash; medians of finite values are
// exact.
TEST(OrderStatisticTest, NaNFallsBackAndMedianIsUpper) {
  std::vector<double> v(100000);
  for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<double>((i * 7919) % v.size());
  std::vector<double> copy = v;
  EXPECT_EQ(UpperMedian(&copy), 50000.0);
  v[123] = std::numeric_limits<double>::quiet_NaN();
  copy = v;
  EXPECT_NO_FATAL_FAILURE(KthSmallest(&copy, 500));
  // Between the sampled values of a log's size, too.
  std::vector<double> log_sized(4345);
  for (size_t i = 0; i < log_sized.size(); ++i) log_sized[i] = static_cast<double>(i);
  log_sized[3] = std::numeric_limits<double>::quiet_NaN();
  copy = log_sized;
  EXPECT_EQ(KthSmallest(&copy, 2000), NthElement(log_sized, 2000));
  std::vector<double> empty;
  EXPECT_EQ(UpperMedian(&empty), 0.0);
}

std::vector<size_t> StableSortedIndices(const std::vector<double>& values) {
  std::vector<size_t> order(values.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return values[a] < values[b]; });
  return order;
}

// The same permutation as std::stable_sort for every kind of array: empty, one value, ties
// (equal values keep their order, −0 and +0 among them), negatives, huge and tiny magnitudes,
// infinities, values that share their high digits, sorted either way.
TEST(OrderStatisticTest, StableOrderEqualsStableSort) {
  Random random(5);
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<std::vector<double>> arrays = {{}, {3.0}, {0.0, -0.0, 0.0, -0.0}, {-inf, 1.0, inf}};
  for (const size_t n : {2, 17, 1000, 5000, 70000}) {  // 8-bit digits, and 11 from 65536.
    std::vector<double> normal(n), ties(n), narrow(n), wide(n), ascending(n), descending(n);
    for (size_t k = 0; k < n; ++k) {
      normal[k] = random.Normal();
      ties[k] = static_cast<double>(random.Index(7)) - 3.0;
      narrow[k] = 1.0 + 1e-12 * random.Uniform();  // Only the low digits differ.
      wide[k] = std::pow(10.0, random.Uniform(-300.0, 300.0)) * (random.Uniform() < 0.5 ? -1 : 1);
      ascending[k] = static_cast<double>(k / 3);
      descending[k] = -ascending[k];
    }
    for (auto* a : {&normal, &ties, &narrow, &wide, &ascending, &descending}) arrays.push_back(*a);
  }
  for (const std::vector<double>& values : arrays) {
    EXPECT_EQ(StableOrder(values), StableSortedIndices(values)) << values.size() << " values";
  }
  // NaN goes last, whatever its sign.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(StableOrder({nan, 2.0, -nan, -inf, 1.0}), (std::vector<size_t>{3, 4, 1, 0, 2}));
}

}  // namespace
}  // namespace calib
