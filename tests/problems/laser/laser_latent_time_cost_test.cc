#include <calib/problems/laser/laser_latent_time_cost.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace calib {
namespace {

// One interval of each kind: blocks 0 odometry, 1 mounting, then its time blocks. The ends share
// an encoder block (the sample after the start's bracket is the one before the end's), and in the
// clock model both ends read the same clock block.
struct Case {
  LatentTimeEnd start, end;
  std::vector<int> sizes;
  std::vector<std::vector<double>> values;
};

Case StampCase() {
  Case c;
  c.sizes = {3, 3, 1, 1, 1, 1, 1};
  c.values = {{0.0206, 0.0207, 0.088},
              {-0.005, 0.006, -1.55},
              {0.004},
              {-0.003},
              {0.002},
              {-0.006},
              {0.001}};
  c.start.time_block = 2, c.start.stamp_s = 10.02;
  c.start.encoder_block = {3, 4};
  c.start.encoder_stamp_s = {9.95, 10.05};
  c.start.left_rad = {1.0, 1.3}, c.start.right_rad = {2.0, 2.1};
  c.end.time_block = 5, c.end.stamp_s = 10.12;
  c.end.encoder_block = {4, 6};
  c.end.encoder_stamp_s = {10.05, 10.15};
  c.end.left_rad = {1.3, 1.55}, c.end.right_rad = {2.1, 2.25};
  // Wheel rates off the secants: the cubic between polls (the sample shared by the ends has one).
  c.start.left_rate = {2.6, 2.8}, c.start.right_rate = {0.9, 1.2};
  c.end.left_rate = {2.8, 2.3}, c.end.right_rate = {1.2, 1.6};
  return c;
}

Case ClockCase() {
  Case c = StampCase();
  c.sizes = {3, 3, 3, 1, 1, 1};
  c.values = {{0.0206, 0.0207, 0.088},
              {-0.005, 0.006, -1.55},
              {0.021, 0.0995, 1e-4},
              {0.002},
              {-0.006},
              {0.001}};
  for (LatentTimeEnd* e : {&c.start, &c.end}) e->clock = true, e->time_block = 2;
  c.start.index = 100.0, c.start.curvature = 0.25;
  c.end.index = 101.0, c.end.curvature = 0.26;
  c.start.encoder_block = {3, 4};
  c.end.encoder_block = {4, 5};
  return c;
}

void ExpectSameAsAutoDiff(const Case& c) {
  const Eigen::Matrix3d sqrt_information = Eigen::Vector3d(2e3, 1.5e3, 4e2).asDiagonal();
  const Pose2d measured(0.0012, -0.0004, 0.011);
  const std::vector<double> interior_left = {1.3}, interior_right = {2.1};
  std::unique_ptr<ceres::CostFunction> hand(LaserLatentTimeCost::Create(
      measured, &sqrt_information, c.start, c.end, interior_left, interior_right, c.sizes));
  std::unique_ptr<ceres::CostFunction> reference(LaserLatentTimeResidual::CreateAutoDiff(
      measured, &sqrt_information, c.start, c.end, interior_left, interior_right, c.sizes));
  std::vector<const double*> parameters;
  for (const std::vector<double>& v : c.values) parameters.push_back(v.data());
  std::vector<std::vector<double>> j_hand, j_reference;
  std::vector<double*> p_hand, p_reference;
  for (const int size : c.sizes) {
    j_hand.emplace_back(3 * size, NAN);
    j_reference.emplace_back(3 * size, NAN);
  }
  for (size_t b = 0; b < c.sizes.size(); ++b) {
    p_hand.push_back(j_hand[b].data());
    p_reference.push_back(j_reference[b].data());
  }
  double r_hand[3] = {NAN, NAN, NAN}, r_reference[3] = {NAN, NAN, NAN}, r_only[3] = {NAN, NAN, NAN};
  ASSERT_TRUE(hand->Evaluate(parameters.data(), r_hand, p_hand.data()));
  ASSERT_TRUE(reference->Evaluate(parameters.data(), r_reference, p_reference.data()));
  ASSERT_TRUE(hand->Evaluate(parameters.data(), r_only, nullptr));
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(r_hand[i], r_reference[i], 1e-12 * (1.0 + std::abs(r_reference[i])));
    EXPECT_NEAR(r_only[i], r_hand[i], 1e-12 * (1.0 + std::abs(r_hand[i])));
  }
  for (size_t b = 0; b < c.sizes.size(); ++b) {
    for (size_t k = 0; k < j_hand[b].size(); ++k) {
      EXPECT_NEAR(j_hand[b][k], j_reference[b][k], 1e-9 * (1.0 + std::abs(j_reference[b][k])))
          << "block " << b << " entry " << k;
    }
  }
  // Blocks Ceres holds constant get no Jacobian (block 3, or the last when there are fewer).
  p_hand[std::min<size_t>(3, p_hand.size() - 1)] = nullptr;
  ASSERT_TRUE(hand->Evaluate(parameters.data(), r_hand, p_hand.data()));
}

TEST(LaserLatentTimeCostTest, StampModelMatchesAutomaticDifferentiation) {
  ExpectSameAsAutoDiff(StampCase());
}

TEST(LaserLatentTimeCostTest, ClockModelMatchesAutomaticDifferentiation) {
  ExpectSameAsAutoDiff(ClockCase());
}

TEST(LaserLatentTimeCostTest, ConstantTimesMatchAutomaticDifferentiation) {
  Case c = StampCase();
  c.sizes = {3, 3};
  c.values.resize(2);
  for (LatentTimeEnd* e : {&c.start, &c.end}) e->time_block = -1, e->encoder_block = {-1, -1};
  ExpectSameAsAutoDiff(c);
}

}  // namespace
}  // namespace calib
