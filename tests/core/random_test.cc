#include <calib/core/random.h>
#include <gtest/gtest.h>

#include <random>

namespace calib {
namespace {

TEST(RandomTest, PolarGaussiansAreFixedForASeed) {
  // Computed once (libstdc++ 12, and this generator); any standard library must give these.
  Random random(1);
  const double expected[4] = {-0.38683176162103994, -0.039399956754155308, 0.68682363917932543,
                              -0.24894784633514505};
  for (double e : expected) EXPECT_EQ(random.NormalPolar(), e);
}

TEST(RandomTest, BoxMullerGaussiansAreFixedForASeedAndStream) {
  Random random(7, 3);
  const double expected[3] = {0.76552276956802678, 1.5895469330333689, 0.76451788522483266};
  for (double e : expected) EXPECT_EQ(random.Normal(), e);
}

#ifdef __GLIBCXX__
TEST(RandomTest, PolarEqualsLibstdcxxNormalDistribution) {
  for (uint64_t seed : {0ull, 1ull, 42ull, 20090101ull}) {
    std::mt19937_64 engine(seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    Random random(seed);
    for (int i = 0; i < 100000; ++i) ASSERT_EQ(random.NormalPolar(), normal(engine)) << i;
  }
}

TEST(RandomTest, CanonicalEqualsGenerateCanonical) {
  std::mt19937_64 engine(5);
  Random random(5);
  for (int i = 0; i < 100000; ++i) {
    ASSERT_EQ(random.Canonical(), (std::generate_canonical<double, 53>(engine))) << i;
  }
}
#endif

TEST(RandomTest, PolarGaussiansHaveUnitVariance) {
  Random random(3);
  double sum = 0.0, sum_sq = 0.0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = random.NormalPolar();
    sum += x;
    sum_sq += x * x;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.01);     // σ/√n ≈ 0.0022.
  EXPECT_NEAR(sum_sq / n, 1.0, 0.02);  // √(2/n) ≈ 0.0032.
}

}  // namespace
}  // namespace calib
