// The bearing time-offset residual: dead reckoning differentiated in its end time, the base term
// at τ = 0, exact at the truth, exact Jacobians, and a two-sided sensitivity on an encoder sample.
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/problems/bearing/bearing_observation_residual.h>
#include <calib/problems/bearing/bearing_time_offset_residual.h>
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "tests/solvers/bearing/bearing_diagnosis_recipes.h"

namespace calib {
namespace {

using ::calib::testing::RecipeOptions;

BearingLog ExactLog(double time_offset_s) {
  BearingSimOptions o = RecipeOptions({"exact", time_offset_s, 3});
  o.encoder_noise_k = 0.0;
  o.bearing_noise_rad = 0.0;
  o.runs[0].duration_s = 60.0;
  return SimulateBearingLog(o);
}

TEST(BearingTimeOffsetModel, IntegrationDifferentiatesTheEndTime) {
  const BearingLog log = ExactLog(0.0);
  const std::vector<EncoderSample>& odometry = log.runs[0].odometry;
  using Jet = ceres::Jet<double, 1>;
  for (double t1 : {10.05, 10.13, 33.33}) {  // Off the samples (a kink there).
    const Pose2<Jet> jet = IntegrateEncoders(odometry, Jet(10.0), Jet(t1, 0), 0.3, 0.5, Jet(1.0),
                                             Jet(1.01), Jet(0.97));
    const Pose2d value = IntegrateEncoders(odometry, 10.0, t1, 0.3, 0.5, 1.0, 1.01, 0.97);
    const double h = 1e-6;
    const Pose2d plus = IntegrateEncoders(odometry, 10.0, t1 + h, 0.3, 0.5, 1.0, 1.01, 0.97);
    const Pose2d minus = IntegrateEncoders(odometry, 10.0, t1 - h, 0.3, 0.5, 1.0, 1.01, 0.97);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(jet(i).a, value(i), 1e-14);
      EXPECT_NEAR(jet(i).v[0], (plus(i) - minus(i)) / (2.0 * h), 1e-7) << t1 << " " << i;
    }
  }
}

TEST(BearingTimeOffsetModel, ReducesToTheBaseAtZeroAndIsExactAtTheTruth) {
  const double tau = 0.15;
  BearingSimTruth truth;
  BearingSimOptions o = RecipeOptions({"exact", tau, 3});
  o.encoder_noise_k = 0.0;
  o.bearing_noise_rad = 0.0;
  o.runs[0].duration_s = 60.0;
  const BearingLog log = SimulateBearingLog(o, &truth);
  const BearingRun& run = log.runs[0];
  const BearingParams& p = truth.params;
  Eigen::Matrix<double, kNumBearingParams, 1> c;
  c << p.phi_rad, p.psi_rad, p.eta_per_m, p.delta, p.xi_per_m;
  const double one = 1.0;
  // Gauge δR ≡ 1: lengths in δR metres.
  const double scale = 1.0 / truth.metric.delta_r;
  double max_at_truth = 0.0, max_without = 0.0;
  for (size_t j = 1; j + 1 < run.bearings.size(); ++j) {
    const BearingSample& b = run.bearings[j];
    // The true pose at the stamp: dead reckoning of the exact encoders from the start.
    const Pose2d start = truth.runs[0].world_T_robot_start;
    Pose2d at_stamp =
        Compose(Pose2d(start(0) * scale, start(1) * scale, start(2)),
                IntegrateEncoders(run.odometry, run.odometry.front().t_s, b.t_s, 0.3, 0.5, 1.0,
                                  c(kBearingDelta), 1.0 / (0.5 * c(kBearingXi))));
    const BearingTimeOffsetResidual model(b.bearing_rad, b.t_s, &run.odometry, 0.3, 0.5, &one);
    const double zero = 0.0;
    // At τ = 0 it is the base term exactly.
    EXPECT_EQ(model.Error(at_stamp.data(), c.data(), &zero),
              BearingObservationResidual::Error(b.bearing_rad, at_stamp.data(), c.data()));
    max_at_truth = std::max(max_at_truth, std::abs(model.Error(at_stamp.data(), c.data(), &tau)));
    max_without = std::max(max_without, std::abs(model.Error(at_stamp.data(), c.data(), &zero)));
  }
  EXPECT_LT(max_at_truth, 1e-9);
  EXPECT_GT(max_without, 1e-3);  // The offset is visible at the true poses.
}

TEST(BearingTimeOffsetModel, JacobianMatchesNumericDifferences) {
  const BearingLog log = ExactLog(0.0);
  const BearingRun& run = log.runs[0];
  const double inverse_sigma = 50.0;
  const BearingSample& b = run.bearings[37];
  std::unique_ptr<ceres::CostFunction> cost(BearingTimeOffsetResidual::Create(
      b.bearing_rad, b.t_s, &run.odometry, 0.3, 0.5, &inverse_sigma));
  double pose[3] = {0.3, -0.8, 0.4};
  double c[kNumBearingParams] = {0.05, 1.5, 1.6, 1.01, 2.0};
  double tau[1] = {0.07};
  double* blocks[3] = {pose, c, tau};
  double residual = 0.0;
  double j_pose[3], j_c[kNumBearingParams], j_tau[1];
  double* jacobians[3] = {j_pose, j_c, j_tau};
  ASSERT_TRUE(cost->Evaluate(blocks, &residual, jacobians));
  const int sizes[3] = {3, kNumBearingParams, 1};
  double* analytic[3] = {j_pose, j_c, j_tau};
  for (int block = 0; block < 3; ++block) {
    for (int k = 0; k < sizes[block]; ++k) {
      const double h = 1e-6, saved = blocks[block][k];
      double plus = 0.0, minus = 0.0;
      blocks[block][k] = saved + h;
      cost->Evaluate(blocks, &plus, nullptr);
      blocks[block][k] = saved - h;
      cost->Evaluate(blocks, &minus, nullptr);
      blocks[block][k] = saved;
      EXPECT_NEAR(analytic[block][k], (plus - minus) / (2.0 * h),
                  1e-5 * std::max(1.0, std::abs(analytic[block][k])))
          << "block " << block << " entry " << k;
    }
  }
}

// A stamp exactly on an encoder sample, where the wheel speeds jump: ∂r/∂τ at τ = 0 is the mean
// of the two one-sided derivatives (the central difference), not the later step's alone.
TEST(BearingTimeOffsetModel, SensitivityIsTwoSidedOnAnEncoderSample) {
  std::vector<EncoderSample> odometry;
  for (int k = 0; k <= 4; ++k) {
    const double t = 0.5 * k;
    // Left 1 rad/s, right 2 rad/s until t = 1 s; then left 3 rad/s, right 1 rad/s.
    const double before = std::min(t, 1.0), after = std::max(t - 1.0, 0.0);
    odometry.push_back({t, before + 3.0 * after, 2.0 * before + after, k + 1});
  }
  const double t_stamp = odometry[2].t_s;
  using Jet = ceres::Jet<double, 1>;
  const Pose2<Jet> jet = IntegrateEncoders(odometry, Jet(t_stamp), Jet(t_stamp, 0), 0.3, 0.5,
                                           Jet(1.0), Jet(1.01), Jet(0.97));
  const double h = 1e-6;
  const Pose2d plus = IntegrateEncoders(odometry, t_stamp, t_stamp + h, 0.3, 0.5, 1.0, 1.01, 0.97);
  const Pose2d minus = IntegrateEncoders(odometry, t_stamp, t_stamp - h, 0.3, 0.5, 1.0, 1.01, 0.97);
  for (int i = 0; i < 3; ++i) {  // O(h) error: the curvature differs on the two sides.
    EXPECT_NEAR(jet(i).v[0], (plus(i) - minus(i)) / (2.0 * h), 1e-5) << i;
  }
  EXPECT_GT(std::abs(jet(2).v[0]), 0.1);  // The heading moves: the test has a kink to see.

  const double inverse_sigma = 50.0;
  std::unique_ptr<ceres::CostFunction> cost(
      BearingTimeOffsetResidual::Create(0.7, t_stamp, &odometry, 0.3, 0.5, &inverse_sigma));
  double pose[3] = {0.3, -0.8, 0.4};
  double c[kNumBearingParams] = {0.05, 1.5, 1.6, 1.01, 2.0};
  double tau[1] = {0.0};
  double* blocks[3] = {pose, c, tau};
  double residual = 0.0, r_plus = 0.0, r_minus = 0.0;
  double j_pose[3], j_c[kNumBearingParams], j_tau[1];
  double* jacobians[3] = {j_pose, j_c, j_tau};
  ASSERT_TRUE(cost->Evaluate(blocks, &residual, jacobians));
  tau[0] = h;
  cost->Evaluate(blocks, &r_plus, nullptr);
  tau[0] = -h;
  cost->Evaluate(blocks, &r_minus, nullptr);
  EXPECT_NEAR(j_tau[0], (r_plus - r_minus) / (2.0 * h), 1e-5 * std::max(1.0, std::abs(j_tau[0])));
}

}  // namespace
}  // namespace calib
