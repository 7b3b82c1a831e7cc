// The bearing bundle adjustment (solvers/bearing_bundle_adjustment.h), its residuals and the
// Cramér–Rao bound, on simulated logs with known truth.
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/problems/bearing/bearing_observation_residual.h>
#include <calib/problems/bearing/bearing_odometry_residual.h>
#include <calib/solvers/bearing/bearing_bundle_adjustment.h>
#include <calib/solvers/bearing/bearing_crlb.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

namespace calib {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Circles at q = 0.5, 0, −1 (one loop each, ~220 bearings): Martinelli's design, shorter.
std::vector<BearingRunSpec> ShortCircles() {
  std::vector<BearingRunSpec> runs = MartinelliRuns();
  runs[0].q = 0.5;
  return runs;
}

// A run whose curvature varies, which no circle fit can handle.
BearingRunSpec NonCircularRun(double duration_s = 300.0) {
  BearingRunSpec spec;
  spec.wheel_speeds = [](double t) {
    const double q = 0.5 + 0.45 * std::sin(2.0 * M_PI * t / 80.0);
    return WheelSpeeds{0.05 * q, 0.05};
  };
  spec.duration_s = duration_s;
  spec.world_T_robot_start = Pose2d(0.0, -1.5, 0.0);
  return spec;
}

BearingLog Simulate(const std::vector<BearingRunSpec>& runs, double sigma_rad, double k,
                    BearingSimTruth* truth, uint64_t seed = 1) {
  BearingSimOptions o;
  o.runs = runs;
  o.bearing_noise_rad = sigma_rad;
  o.encoder_noise_k = k;
  o.seed = seed;
  return SimulateBearingLog(o, truth);
}

// The true poses at the nodes of every run, in gauge units (δR ≡ 1).
std::vector<std::vector<Pose2d>> TruePoses(const BearingLog& log, const BearingSimTruth& truth) {
  const std::vector<BearingRunNodes> nodes = BearingNodes(log);
  std::vector<std::vector<Pose2d>> poses(log.runs.size());
  for (size_t i = 0; i < log.runs.size(); ++i) {
    for (int b : nodes[i].bearing) {
      Pose2d p =
          b < 0 ? truth.runs[i].world_T_robot_start : truth.runs[i].world_T_robot_at_bearings[b];
      p.head<2>() /= truth.metric.delta_r;
      poses[i].push_back(p);
    }
  }
  return poses;
}

BearingParams Perturbed(const BearingParams& p) {
  BearingParams q = p;
  q.phi_rad += 3.0 * kDeg;
  q.psi_rad -= 3.0 * kDeg;
  q.eta_per_m *= 1.05;
  q.delta *= 1.003;
  q.xi_per_m *= 0.995;
  return q;
}

// Seed poses: the true start landmarks, slightly off, dead-reckoned with the seed calibration.
std::vector<std::vector<Pose2d>> SeedPoses(const BearingLog& log, const BearingSimTruth& truth,
                                           const BearingParams& seed) {
  std::vector<Eigen::Vector2d> landmarks;
  for (const BearingRunTruth& run : truth.runs) {
    Pose2d start = run.world_T_robot_start;
    start.head<2>() /= truth.metric.delta_r;
    const Pose2d landmark = Compose(Inverse(start), Pose2d(0.0, 0.0, 0.0));
    landmarks.push_back(landmark.head<2>() * 1.03 + Eigen::Vector2d(0.02, -0.02));
  }
  return DeadReckonedPoses(log, seed, landmarks);
}

void ExpectParamsNear(const BearingParams& a, const BearingParams& b, double tol) {
  const BearingParamVector va = ToVector(a), vb = ToVector(b);
  for (int i = 0; i < kNumBearingParams; ++i) {
    const double scale = i < 2 ? 1.0 : std::abs(vb(i));
    EXPECT_NEAR((i < 2 ? WrapAngle(va(i) - vb(i)) : va(i) - vb(i)) / scale, 0.0, tol)
        << kBearingParamNames[i];
  }
}

// ---------------------------------------------------------------------------------------------
// Residuals.

TEST(BearingResidualTest, VanishAtTheTruthOnNoiseFreeData) {
  BearingSimTruth truth;
  const BearingLog log = Simulate(ShortCircles(), 0.0, 0.0, &truth);
  const std::vector<BearingRunNodes> nodes = BearingNodes(log);
  const std::vector<std::vector<Pose2d>> poses = TruePoses(log, truth);
  const BearingParamVector c = ToVector(truth.params);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  for (size_t i = 0; i < log.runs.size(); ++i) {
    for (size_t k = 0; k < nodes[i].t_s.size(); ++k) {
      if (nodes[i].bearing[k] >= 0) {
        const double beta = log.runs[i].bearings[nodes[i].bearing[k]].bearing_rad;
        EXPECT_NEAR(BearingObservationResidual::Error(beta, poses[i][k].data(), c.data()), 0.0,
                    1e-9);
      }
      if (k == 0) continue;
      const BearingOdometryResidual odometry(&log.runs[i].odometry, nodes[i].t_s[k - 1],
                                             nodes[i].t_s[k], log.meta.wheel_radius_m,
                                             log.meta.wheelbase_m, &identity);
      EXPECT_LT(odometry.Error(poses[i][k - 1].data(), poses[i][k].data(), c.data()).norm(), 1e-9);
    }
  }
}

// Both cost functions' Jacobians (the odometry one chains 2-component Jets) against central
// differences, at a point away from the truth.
TEST(BearingResidualTest, JacobiansMatchCentralDifferences) {
  BearingSimTruth truth;
  const BearingLog log = Simulate(ShortCircles(), 1.0 * kDeg, 1e-3, &truth, 3);
  const std::vector<BearingRunNodes> nodes = BearingNodes(log);
  BearingParamVector c = ToVector(Perturbed(truth.params));
  Pose2d x0(0.3, -0.9, 0.2), x1(0.33, -0.87, 0.25);
  Eigen::Matrix3d sqrt_information;
  sqrt_information << 40.0, 3.0, -2.0, 0.0, 55.0, 7.0, 0.0, 0.0, 90.0;
  const double inverse_sigma = 1.0 / (1.0 * kDeg);
  std::unique_ptr<ceres::CostFunction> odometry(BearingOdometryResidual::Create(
      &log.runs[0].odometry, nodes[0].t_s[5], nodes[0].t_s[6], log.meta.wheel_radius_m,
      log.meta.wheelbase_m, &sqrt_information));
  std::unique_ptr<ceres::CostFunction> bearing(
      BearingObservationResidual::Create(log.runs[0].bearings[5].bearing_rad, &inverse_sigma));

  std::vector<double*> blocks = {x0.data(), x1.data(), c.data()};
  const std::vector<int> sizes = {3, 3, kNumBearingParams};
  for (int which = 0; which < 2; ++which) {
    ceres::CostFunction* cost = which == 0 ? odometry.get() : bearing.get();
    const int m = cost->num_residuals();
    const std::vector<double*> params =
        which == 0 ? blocks : std::vector<double*>{x0.data(), c.data()};
    const std::vector<int> param_sizes =
        which == 0 ? sizes : std::vector<int>{3, kNumBearingParams};
    std::vector<std::vector<double>> jac(params.size());
    std::vector<double*> jac_ptr;
    for (size_t b = 0; b < params.size(); ++b) {
      jac[b].resize(m * param_sizes[b]);
      jac_ptr.push_back(jac[b].data());
    }
    std::vector<double> r(m), rp(m), rm(m);
    ASSERT_TRUE(cost->Evaluate(params.data(), r.data(), jac_ptr.data()));
    for (size_t b = 0; b < params.size(); ++b) {
      for (int p = 0; p < param_sizes[b]; ++p) {
        const double h = 1e-6 * std::max(1.0, std::abs(params[b][p]));
        const double saved = params[b][p];
        params[b][p] = saved + h;
        cost->Evaluate(params.data(), rp.data(), nullptr);
        params[b][p] = saved - h;
        cost->Evaluate(params.data(), rm.data(), nullptr);
        params[b][p] = saved;
        for (int i = 0; i < m; ++i) {
          const double numeric = (rp[i] - rm[i]) / (2.0 * h);
          const double analytic = jac[b][i * param_sizes[b] + p];
          EXPECT_NEAR(analytic, numeric, 1e-5 * (1.0 + std::abs(numeric)))
              << (which == 0 ? "odometry" : "bearing") << " block " << b << " param " << p
              << " residual " << i;
        }
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Exact recovery from a perturbed seed.

TEST(BearingBundleAdjustmentTest, RecoversNoiseFreeCirclesFromPerturbedSeed) {
  BearingSimTruth truth;
  BearingSimOptions o;
  o.encoder_noise_k = 0.0;
  o.bearing_noise_rad = 0.0;
  const BearingLog log = SimulateBearingLog(o, &truth);  // Martinelli's §8.1 runs.
  const BearingParams seed = Perturbed(truth.params);
  BearingProblem problem(log, seed, SeedPoses(log, truth, seed), BearingNoise{1e-3, 1e-3});
  ASSERT_TRUE(problem.Solve().ok());
  ExpectParamsNear(problem.params(), truth.params, 1e-7);
  // The poses too (up to each run's turn about the landmark, fixed by its start on the y axis).
  const std::vector<std::vector<Pose2d>> poses = problem.poses();
  const std::vector<std::vector<Pose2d>> true_poses = TruePoses(log, truth);
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(poses[i].front()(0), 0.0);
    for (size_t k = 0; k < poses[i].size(); k += 37) {
      EXPECT_NEAR(poses[i][k].head<2>().norm(), true_poses[i][k].head<2>().norm(), 1e-7);
    }
  }
  EXPECT_NEAR(problem.StartDistance(0), 1.0 / truth.metric.delta_r, 1e-7);
}

TEST(BearingBundleAdjustmentTest, RecoversNoiseFreeNonCircularRunFromPerturbedSeed) {
  BearingSimTruth truth;
  const BearingLog log = Simulate({NonCircularRun()}, 0.0, 0.0, &truth);
  const BearingParams seed = Perturbed(truth.params);
  BearingProblem problem(log, seed, SeedPoses(log, truth, seed), BearingNoise{1e-3, 1e-3});
  ASSERT_TRUE(problem.Solve().ok());
  ExpectParamsNear(problem.params(), truth.params, 1e-7);
}

// ---------------------------------------------------------------------------------------------
// Covariance, leverages, bound.

TEST(BearingBundleAdjustmentTest, LeveragesSumToTheFreeParametersAndNoiseIsRecovered) {
  BearingSimTruth truth;
  const BearingLog log = Simulate(ShortCircles(), 2.0 * kDeg, 1e-3, &truth, 5);
  BearingProblem problem(log, truth.params, TruePoses(log, truth), BearingNoise{2.0 * kDeg, 1e-3});
  ASSERT_TRUE(problem.Solve().ok());
  std::vector<std::vector<bool>> inlier;
  int free_parameters = kNumBearingParams;
  for (size_t i = 0; i < log.runs.size(); ++i) {
    inlier.emplace_back(log.runs[i].bearings.size(), true);
    free_parameters += 3 * static_cast<int>(problem.nodes()[i].t_s.size()) - 1;
  }
  const StatusOr<BearingVarianceComponents> vc = problem.VarianceComponents(inlier);
  ASSERT_TRUE(vc.ok()) << vc.message();
  EXPECT_NEAR(vc->total_leverage, free_parameters, 1e-6 * free_parameters);
  // σβ from the bearings' residuals over their redundancy.
  EXPECT_NEAR(std::sqrt(vc->bearing_sum_sq_rad2 / vc->bearing_redundancy) / (2.0 * kDeg), 1.0,
              0.12);
  EXPECT_GT(vc->odometry_redundancy, 0.0);
}

// ceres::Covariance orders its columns by the parameter blocks' addresses: the same problem built
// where the heap has other holes (another thread's allocations do that) gives the same bits.
TEST(BearingBundleAdjustmentTest, CovarianceDoesNotDependOnWhereTheHeapPutsTheProblem) {
  BearingSimTruth truth;
  const BearingLog log = Simulate(ShortCircles(), 2.0 * kDeg, 1e-3, &truth, 5);
  const auto covariance = [&] {
    BearingProblem problem(log, truth.params, TruePoses(log, truth),
                           BearingNoise{2.0 * kDeg, 1e-3});
    EXPECT_TRUE(problem.Solve().ok());
    const auto cov = problem.CalibrationCovarianceWithStartDistance(2);
    EXPECT_TRUE(cov.ok()) << cov.message();
    return cov.ok() ? Eigen::MatrixXd(cov->covariance) : Eigen::MatrixXd();
  };
  const Eigen::MatrixXd first = covariance();
  for (size_t hole : {size_t{1} << 10, size_t{3} << 12, size_t{5} << 13}) {
    // Blocks of the size of a run's poses, every other one freed: holes low in the heap.
    std::vector<std::unique_ptr<char[]>> blocks;
    for (int i = 0; i < 64; ++i) blocks.emplace_back(new char[hole]);
    for (size_t i = 0; i < blocks.size(); i += 2) blocks[i].reset();
    const Eigen::MatrixXd again = covariance();
    ASSERT_EQ(again.size(), first.size());
    EXPECT_TRUE((again.array() == first.array()).all()) << hole << "\n" << (again - first);
  }
}

TEST(BearingCrlbTest, ScalesWithBearingNoiseAndGrowsWithEncoderNoise) {
  BearingSimTruth truth;
  const BearingLog log = Simulate(MartinelliRuns(), 1.0 * kDeg, 1e-3, &truth);
  const StatusOr<BearingBound> b1 = BearingCramerRaoBound(log, truth, {1.0 * kDeg, 1e-9});
  const StatusOr<BearingBound> b2 = BearingCramerRaoBound(log, truth, {2.0 * kDeg, 1e-9});
  const StatusOr<BearingBound> bk = BearingCramerRaoBound(log, truth, {1.0 * kDeg, 1e-3});
  ASSERT_TRUE(b1.ok() && b2.ok() && bk.ok()) << b1.message();
  for (int i = 0; i < kNumBearingParams; ++i) {
    EXPECT_NEAR(b2->stddev(i) / b1->stddev(i), 2.0, 1e-3) << kBearingParamNames[i];
    EXPECT_GE(bk->stddev(i), b1->stddev(i)) << kBearingParamNames[i];
  }
  // The encoder noise limits δ (the period of the long q = 0.9 loop) most.
  EXPECT_GT(bk->stddev(kBearingDelta) / b1->stddev(kBearingDelta), 1.5);
  EXPECT_FALSE(bk->has_metric);
}

TEST(BearingCrlbTest, MetricBoundFollowsFromTheInitialDistance) {
  BearingSimTruth truth;
  BearingSimOptions o;
  o.runs = ShortCircles();
  o.bearing_noise_rad = 1.0 * kDeg;
  o.initial_distance_run = 2;
  const BearingLog log = SimulateBearingLog(o, &truth);
  const StatusOr<BearingBound> b = BearingCramerRaoBound(log, truth, {1.0 * kDeg, 1e-3});
  ASSERT_TRUE(b.ok()) << b.message();
  ASSERT_TRUE(b->has_metric);
  EXPECT_NEAR(b->metric_stddev(0), b->stddev(kBearingPhi), 1e-12);
  for (int i = 2; i < kNumBearingMetricParams; ++i) EXPECT_GT(b->metric_stddev(i), 0.0);
}

TEST(BearingGaugeTest, MetricFromScaledInvertsTheObservableSetWithItsJacobian) {
  const BearingMetricParams m{0.1, 0.3, 1.4, 0.99, 1.006, 0.97};
  const double wheelbase = 0.5, d0 = 1.7;
  const BearingParams p = ObservableParams(m, wheelbase);
  const double d0_gauge = d0 / m.delta_r;
  Eigen::Matrix<double, kNumBearingMetricParams, kNumBearingParams + 1> jacobian;
  const BearingMetricParams back = BearingMetricFromScaled(p, d0_gauge, d0, wheelbase, &jacobian);
  EXPECT_NEAR((ToVector(back) - ToVector(m)).norm(), 0.0, 1e-12);
  BearingScaledWithDistance x;
  x << ToVector(p), d0_gauge;
  for (int j = 0; j < kNumBearingParams + 1; ++j) {
    const double h = 1e-6;
    BearingScaledWithDistance xp = x, xm = x;
    xp(j) += h, xm(j) -= h;
    const BearingMetricVector fp = ToVector(BearingMetricFromScaled(
        BearingParamsFromVector(xp.head<kNumBearingParams>()), xp(5), d0, wheelbase));
    const BearingMetricVector fm = ToVector(BearingMetricFromScaled(
        BearingParamsFromVector(xm.head<kNumBearingParams>()), xm(5), d0, wheelbase));
    for (int i = 0; i < kNumBearingMetricParams; ++i) {
      EXPECT_NEAR(jacobian(i, j), (fp(i) - fm(i)) / (2 * h), 1e-6) << i << "," << j;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Degenerate input.

TEST(BearingBundleAdjustmentTest, TwoCirclesDoNotDetermineTheCalibration) {
  BearingSimTruth truth;
  std::vector<BearingRunSpec> runs = MartinelliRuns();
  runs.erase(runs.begin());  // q = 0 and −1 only: 8 observables for 9 unknowns.
  const BearingLog log = Simulate(runs, 1.0 * kDeg, 1e-3, &truth);
  const StatusOr<BearingBound> b = BearingCramerRaoBound(log, truth, {1.0 * kDeg, 1e-3});
  ASSERT_FALSE(b.ok());
  EXPECT_NE(b.message().find("does not determine"), std::string::npos) << b.message();
}

TEST(BearingBundleAdjustmentTest, NodesAddTheStartWhenNoBearingIsTakenThere) {
  BearingSimTruth truth;
  BearingLog log = Simulate(ShortCircles(), 0.0, 0.0, &truth);
  log.runs[1].bearings.erase(log.runs[1].bearings.begin());
  const std::vector<BearingRunNodes> nodes = BearingNodes(log);
  EXPECT_EQ(nodes[0].bearing.front(), 0);
  EXPECT_EQ(nodes[1].bearing.front(), -1);
  EXPECT_EQ(nodes[1].t_s.front(), log.runs[1].odometry.front().t_s);
  EXPECT_EQ(nodes[1].t_s.size(), log.runs[1].bearings.size() + 1);
}

}  // namespace
}  // namespace calib
