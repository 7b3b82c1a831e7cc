// Holm's step-down procedure (solvers/diagnosis/multiple_testing.h) on known p-values.
#include <calib/solvers/diagnosis/multiple_testing.h>
#include <gtest/gtest.h>

namespace calib {
namespace {

TEST(HolmTest, StepsDownUntilTheFirstAcceptance) {
  // α = 0.05, m = 4: levels 0.0125, 0.0167, 0.025, 0.05 in ascending order of p.
  const std::vector<double> p = {0.04, 0.001, 0.03, 0.012};
  const std::vector<HolmStep> steps = Holm(p, 0.05);
  ASSERT_EQ(steps.size(), 4u);
  EXPECT_EQ(steps[0].index, 1u);
  EXPECT_EQ(steps[1].index, 3u);
  EXPECT_EQ(steps[2].index, 2u);
  EXPECT_EQ(steps[3].index, 0u);
  EXPECT_DOUBLE_EQ(steps[0].level, 0.0125);
  EXPECT_DOUBLE_EQ(steps[1].level, 0.05 / 3.0);
  EXPECT_DOUBLE_EQ(steps[2].level, 0.025);
  EXPECT_DOUBLE_EQ(steps[3].level, 0.05);
  EXPECT_TRUE(steps[0].rejected);
  EXPECT_TRUE(steps[1].rejected);   // 0.012 ≤ 0.0167.
  EXPECT_FALSE(steps[2].rejected);  // 0.03 > 0.025 stops the procedure ...
  EXPECT_FALSE(steps[3].rejected);  // ... although 0.04 ≤ 0.05.
}

TEST(HolmTest, TiesKeepTheirOrderAndEmptyIsEmpty) {
  const std::vector<HolmStep> steps = Holm({0.0, 0.0, 0.5}, 0.01);
  EXPECT_EQ(steps[0].index, 0u);
  EXPECT_EQ(steps[1].index, 1u);
  EXPECT_TRUE(steps[1].rejected);
  EXPECT_FALSE(steps[2].rejected);
  EXPECT_TRUE(Holm({}, 0.01).empty());
}

}  // namespace
}  // namespace calib
