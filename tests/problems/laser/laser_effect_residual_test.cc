// The laser problem's candidate effects as one residual: it reduces to the base residual at γ = 0,
// explains each simulated effect exactly, absorbs the confounded ones, and has exact Jacobians.
#include <calib/core/laser/laser_simulator.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/problems/laser/laser_residual.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "tests/problems/laser/laser_effect_gamma.h"

namespace calib {
namespace {

using ::calib::testing::EffectVector;
using ::calib::testing::Gamma;

// A noise-free log with constant speeds per interval: the models are exact for it.
LaserSimOptions ExactOptions(int intervals, uint64_t seed) {
  LaserSimOptions sim;
  sim.num_intervals = intervals;
  sim.seed = seed;
  sim.speed_time_constant_s = 0.0;
  sim.segment_mean_s = 1.5;  // Frequent speed changes, where the boundary effects act.
  sim.scan_noise_sigma.setZero();
  return sim;
}

double MaxAbsResidual(const std::vector<LaserInterval>& intervals, const LaserSimOptions& sim,
                      const EffectVector& gamma, double change_time_s) {
  const std::vector<LaserEffectContext> contexts =
      BuildLaserEffectContexts(intervals, BoundarySpeedModel::kPiecewiseConstant, change_time_s);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const double odometry[3] = {sim.odometry.left_radius_m, sim.odometry.right_radius_m,
                              sim.odometry.wheelbase_m};
  const Pose2d& m = sim.base_T_sensor;
  const double mounting[3] = {m(0), m(1), m(2)};
  double worst = 0.0;
  for (const LaserEffectContext& context : contexts) {
    double residual[3];
    EXPECT_TRUE(
        LaserEffectResidual(context, &identity)(odometry, mounting, gamma.data(), residual));
    for (double r : residual) worst = std::max(worst, std::abs(r));
  }
  return worst;
}

TEST(LaserEffectResidualTest, EqualsTheBaseResidualAtZero) {
  LaserSimOptions sim = ExactOptions(300, 5);
  sim.scan_noise_sigma = Eigen::Vector3d(1e-3, 1e-3, 2e-3);
  sim.record_steps = 0;
  LaserLog log = SimulateLaserLog(sim);
  // Every other interval through the stepped (non-constant speed) model, as the base does.
  for (size_t k = 0; k < log.intervals.size(); k += 2) {
    LaserInterval& in = log.intervals[k];
    const double t = in.duration_s;
    in.steps = {{0.3 * t, 0.2 * in.left_speed * t, 0.5 * in.right_speed * t},
                {0.7 * t, 0.8 * in.left_speed * t, 0.5 * in.right_speed * t}};
  }
  const Eigen::Matrix3d sqrt_information = Eigen::Vector3d(1e3, 2e3, 5e2).asDiagonal();
  double odometry[3] = {0.021, 0.0205, 0.09};
  double mounting[3] = {0.01, -0.02, 0.7};
  double gamma[kNumLaserEffectParams] = {};
  for (BoundarySpeedModel model :
       {BoundarySpeedModel::kPiecewiseConstant, BoundarySpeedModel::kSmooth}) {
    // A change time inside the log: with γ = 0 it must not matter either.
    const std::vector<LaserEffectContext> contexts =
        BuildLaserEffectContexts(log.intervals, model, 100.3);
    for (size_t k = 0; k < contexts.size(); ++k) {
      std::unique_ptr<ceres::CostFunction> base(
          LaserResidual::Create(log.intervals[k], &sqrt_information));
      std::unique_ptr<ceres::CostFunction> effect(
          LaserEffectResidual::Create(contexts[k], &sqrt_information));
      double r_base[3], r_effect[3], j_base[2][9], j_effect[3][3 * kNumLaserEffectParams];
      double* base_parameters[2] = {odometry, mounting};
      double* effect_parameters[3] = {odometry, mounting, gamma};
      double* base_jacobians[2] = {j_base[0], j_base[1]};
      double* effect_jacobians[3] = {j_effect[0], j_effect[1], j_effect[2]};
      ASSERT_TRUE(base->Evaluate(base_parameters, r_base, base_jacobians));
      ASSERT_TRUE(effect->Evaluate(effect_parameters, r_effect, effect_jacobians));
      for (int i = 0; i < 3; ++i) EXPECT_EQ(r_base[i], r_effect[i]) << "interval " << k;
      for (int b = 0; b < 2; ++b) {
        for (int i = 0; i < 9; ++i) {
          EXPECT_NEAR(j_base[b][i], j_effect[b][i], 1e-12 * (1.0 + std::abs(j_base[b][i])))
              << "interval " << k << " block " << b << " entry " << i;
        }
      }
    }
  }
}

TEST(LaserEffectResidualTest, ZeroAtTheTruthOfEachSimulatedEffect) {
  struct Case {
    const char* name;
    LaserEffects effects;
    EffectVector gamma;
    double change_time_s = std::numeric_limits<double>::infinity();
  };
  const LaserSimOptions base = ExactOptions(600, 3);
  const OdometryParams& o = base.odometry;
  std::vector<Case> cases;
  for (double offset : {0.035, -0.025}) {
    Case c{"time_offset", {}, Gamma(LaserEffect::kTimeOffset, offset)};
    c.effects.time_offset_s = offset;
    cases.push_back(c);
  }
  {
    Case c{"lateral_slip", {}, Gamma(LaserEffect::kLateralSlip, 0.8)};
    c.effects.lateral_slip_s = 0.8;
    cases.push_back(c);
  }
  {
    Case c{"longitudinal_slip", {}, Gamma(LaserEffect::kLongitudinalSlip, 0.3)};
    c.effects.longitudinal_slip_s = 0.3;
    cases.push_back(c);
  }
  {
    const double after_l = o.left_radius_m * 1.02, after_r = o.right_radius_m * 0.99;
    Case c{"wheel_radius_change",
           {},
           Gamma(LaserEffect::kWheelRadiusChange, after_l / o.left_radius_m - 1.0,
                 after_r / o.right_radius_m - 1.0)};
    c.effects.radius_change_time_s = 203.7;  // Inside an interval.
    c.effects.left_radius_after_m = after_l;
    c.effects.right_radius_after_m = after_r;
    c.change_time_s = 203.7;
    cases.push_back(c);
  }
  for (const Case& c : cases) {
    LaserSimOptions sim = base;
    sim.effects = c.effects;
    const LaserLog log = SimulateLaserLog(sim);
    // The effect is visible to the base model...
    EXPECT_GT(MaxAbsResidual(log.intervals, sim, EffectVector::Zero(), c.change_time_s), 1e-5)
        << c.name;
    // ...and its model explains the simulation to rounding.
    EXPECT_LT(MaxAbsResidual(log.intervals, sim, c.gamma, c.change_time_s), 1e-12) << c.name;
  }
}

// The two omissions the data cannot see: exactly a change of the base parameters.
TEST(LaserEffectResidualTest, ConfoundedEffectsAreExactlyAbsorbed) {
  const LaserLog log = SimulateLaserLog(ExactOptions(200, 8));
  const std::vector<LaserEffectContext> contexts =
      BuildLaserEffectContexts(log.intervals, BoundarySpeedModel::kSmooth);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const double odometry[3] = {0.0206, 0.0207, 0.088};
  const double mounting[3] = {-0.005, 0.006, -1.55};
  const double offset = 0.013, scale = 0.02;
  // ICR at x = offset: the sensor seen from the no-slip point sits at x − offset.
  const double icr_mounting[3] = {mounting[0] - offset, mounting[1], mounting[2]};
  // Scan scale 1 + s: every length scaled by 1 + s.
  const double k = 1.0 + scale;
  const double scaled_odometry[3] = {odometry[0] * k, odometry[1] * k, odometry[2] * k};
  const double scaled_mounting[3] = {mounting[0] * k, mounting[1] * k, mounting[2]};
  const EffectVector zero = EffectVector::Zero();
  const EffectVector icr = Gamma(LaserEffect::kIcrOffset, offset);
  const EffectVector scan = Gamma(LaserEffect::kScanScale, scale);
  for (const LaserEffectContext& context : contexts) {
    double with_icr[3], base_icr[3], with_scale[3], base_scale[3];
    LaserEffectResidual(context, &identity)(odometry, mounting, icr.data(), with_icr);
    LaserEffectResidual(context, &identity)(odometry, icr_mounting, zero.data(), base_icr);
    LaserEffectResidual(context, &identity)(odometry, mounting, scan.data(), with_scale);
    LaserEffectResidual(context, &identity)(scaled_odometry, scaled_mounting, zero.data(),
                                            base_scale);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(with_icr[i], base_icr[i], 1e-15);
      EXPECT_NEAR(with_scale[i], base_scale[i], 1e-15);
    }
  }
}

TEST(LaserEffectResidualTest, JacobiansMatchCentralDifferences) {
  LaserSimOptions sim = ExactOptions(120, 21);
  sim.scan_noise_sigma = Eigen::Vector3d(1e-3, 1e-3, 2e-3);
  LaserLog log = SimulateLaserLog(sim);
  log.intervals[7].steps = {{0.3, 0.1, 0.2}, {0.5, -0.05, 0.3}};
  const Eigen::Matrix3d sqrt_information = Eigen::Vector3d(1e3, 1e3, 5e2).asDiagonal();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (BoundarySpeedModel model :
       {BoundarySpeedModel::kPiecewiseConstant, BoundarySpeedModel::kSmooth}) {
    const std::vector<LaserEffectContext> contexts =
        BuildLaserEffectContexts(log.intervals, model, log.intervals[40].start_s + 0.3);
    for (size_t k = 0; k < contexts.size(); k += 3) {
      std::vector<double> odometry = {0.021, 0.020, 0.09};
      std::vector<double> mounting = {0.01, -0.02, 0.3 * unit(rng)};
      // Away from γ = 0 (the time offset's kink) and with every effect on.
      std::vector<double> gamma = {0.02 + 0.01 * unit(rng), 0.5 * unit(rng),  0.2 * unit(rng),
                                   0.01 * unit(rng),        0.01 * unit(rng), 0.05 * unit(rng),
                                   0.01 * unit(rng),        0.01 * unit(rng), 0.01 * unit(rng)};
      std::vector<double>* blocks[3] = {&odometry, &mounting, &gamma};
      std::unique_ptr<ceres::CostFunction> cost(
          LaserEffectResidual::Create(contexts[k], &sqrt_information));
      double* parameters[3] = {odometry.data(), mounting.data(), gamma.data()};
      double residual[3];
      std::vector<std::vector<double>> jacobians = {std::vector<double>(9), std::vector<double>(9),
                                                    std::vector<double>(3 * kNumLaserEffectParams)};
      double* jacobian_ptrs[3] = {jacobians[0].data(), jacobians[1].data(), jacobians[2].data()};
      ASSERT_TRUE(cost->Evaluate(parameters, residual, jacobian_ptrs));
      for (int b = 0; b < 3; ++b) {
        const int size = static_cast<int>(blocks[b]->size());
        for (int i = 0; i < size; ++i) {
          double& x = (*blocks[b])[i];
          const double h = 1e-6 * std::max(1e-3, std::abs(x));
          const double saved = x;
          double plus[3], minus[3];
          x = saved + h;
          cost->Evaluate(parameters, plus, nullptr);
          x = saved - h;
          cost->Evaluate(parameters, minus, nullptr);
          x = saved;
          for (int r = 0; r < 3; ++r) {
            const double numeric = (plus[r] - minus[r]) / (2.0 * h);
            const double analytic = jacobians[b][r * size + i];
            EXPECT_NEAR(analytic, numeric, 1e-5 * (1.0 + std::abs(numeric)))
                << "interval " << k << " block " << b << " parameter " << i << " residual " << r;
          }
        }
      }
    }
  }
}

TEST(LaserEffectResidualTest, BoundarySpeedsFromPolynomialsAreExact) {
  // Cumulative angle Φ(t) = t³ − t: the 7-node derivative is exact for polynomials to degree 6.
  const std::vector<double> nodes = {0.0, 0.7, 1.5, 2.4, 3.1, 3.9, 4.8};
  const std::vector<double> weights = DerivativeWeights(nodes, 2.4);
  double derivative = 0.0;
  for (size_t j = 0; j < nodes.size(); ++j) {
    derivative += weights[j] * (std::pow(nodes[j], 3) - nodes[j]);
  }
  EXPECT_NEAR(derivative, 3 * 2.4 * 2.4 - 1.0, 1e-10);
  // At each node, the barycentric form gives the same weights.
  for (size_t k = 0; k < nodes.size(); ++k) {
    const std::vector<double> general = DerivativeWeights(nodes, nodes[k]);
    const std::vector<double> at_node = NodeDerivativeWeights(nodes, k);
    for (size_t j = 0; j < nodes.size(); ++j) {
      EXPECT_NEAR(at_node[j], general[j], 1e-12 * (1.0 + std::abs(general[j])))
          << "node " << k << " weight " << j;
    }
  }
  // At an isolated speed jump the smooth model takes the mean of the two sides.
  std::vector<LaserInterval> intervals(8);
  for (size_t k = 0; k < intervals.size(); ++k) {
    intervals[k].start_s = 0.8 * k;
    intervals[k].duration_s = 0.8;
    intervals[k].left_speed = intervals[k].right_speed = k < 4 ? 0.2 : 0.6;
  }
  const std::vector<LaserEffectContext> contexts =
      BuildLaserEffectContexts(intervals, BoundarySpeedModel::kSmooth);
  EXPECT_NEAR(contexts[4].start.before(0), 0.4, 1e-12);
  EXPECT_NEAR(contexts[4].start.after(1), 0.4, 1e-12);
  const std::vector<LaserEffectContext> piecewise =
      BuildLaserEffectContexts(intervals, BoundarySpeedModel::kPiecewiseConstant);
  EXPECT_EQ(piecewise[4].start.before(0), 0.2);
  EXPECT_EQ(piecewise[4].start.after(0), 0.6);
}

}  // namespace
}  // namespace calib
