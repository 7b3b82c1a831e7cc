#include <calib/core/laser/laser_simulator.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/common/fused_normal_cost.h>
#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/common/robust_loss.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_refinement.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

namespace calib {
namespace {

LaserRefinementOptions PerInterval(LaserRefinementOptions options = {}) {
  options.per_interval_blocks = true;
  return options;
}

LaserLog NoisyLogWithSlips(int intervals, int seed) {
  LaserSimOptions sim;
  sim.num_intervals = intervals;
  sim.outlier_fraction = 0.05;
  sim.seed = seed;
  return SimulateLaserLog(sim);
}

// The dataset whitened by the calibration's own noise level, as CalibrateLaser builds it.
LaserDataset Whitened(const LaserLog& log, const LaserCalibrationResult& result) {
  return LaserDataset{&log.intervals, result.noise_sigma[0].cwiseInverse().asDiagonal()};
}

// Ceres' cost, gradient and Gauss–Newton matrix of a problem at its current parameters.
struct Linearization {
  double cost = 0.0;
  Eigen::VectorXd gradient;
  Eigen::MatrixXd gauss_newton;
};

Linearization Linearize(ceres::Problem* problem) {
  Linearization out;
  std::vector<double> gradient;
  ceres::CRSMatrix jacobian;
  EXPECT_TRUE(problem->Evaluate(ceres::Problem::EvaluateOptions(), &out.cost, nullptr, &gradient,
                                &jacobian));
  out.gradient = Eigen::Map<Eigen::VectorXd>(gradient.data(), gradient.size());
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(jacobian.num_rows, jacobian.num_cols);
  for (int row = 0; row < jacobian.num_rows; ++row) {
    for (int i = jacobian.rows[row]; i < jacobian.rows[row + 1]; ++i) {
      dense(row, jacobian.cols[i]) = jacobian.values[i];
    }
  }
  out.gauss_newton = dense.transpose() * dense;
  return out;
}

// A loss with ρ'' > 0 (no loss here has one), to exercise Ceres' curvature correction.
class ConvexLoss : public ceres::LossFunction {
 public:
  void Evaluate(double s, double rho[3]) const override {
    rho[0] = s + 0.05 * s * s;
    rho[1] = 1.0 + 0.1 * s;
    rho[2] = 0.1;
  }
};

// Ceres sees the same cost, gradient and Gauss–Newton matrix from the one fused block as from a
// block per interval, for a loss with ρ'' < 0 (Cauchy), without a loss, and with ρ'' > 0 (the
// cost is then not exact: e² would be negative; the gradient and matrix are).
TEST(FusedNormalCostTest, CeresSeesTheSameLinearizationAsFromSeparateBlocks) {
  const LaserLog log = NoisyLogWithSlips(500, 3);
  const Eigen::Matrix3d root = Eigen::Vector3d(1e3, 1e3, 5e2).asDiagonal();
  // Off the optimum, so the gradient is not small.
  const double odometry_init[3] = {0.033, 0.031, 0.31};
  const double sensor_init[3] = {0.1, 0.02, 0.3};
  ceres::CauchyLoss cauchy(3.0);
  ConvexLoss convex;
  const std::vector<std::pair<const ceres::LossFunction*, bool>> losses = {
      {&cauchy, true}, {nullptr, true}, {&convex, false}};
  for (const auto& [loss, cost_exact] : losses) {
    ceres::Problem::Options options;
    options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem separate(options), fused(options);
    double odometry[2][3], sensor[2][3];
    for (int p = 0; p < 2; ++p) {
      std::copy(odometry_init, odometry_init + 3, odometry[p]);
      std::copy(sensor_init, sensor_init + 3, sensor[p]);
    }
    for (const LaserInterval& interval : log.intervals) {
      separate.AddResidualBlock(LaserResidual::Create(interval, &root),
                                const_cast<ceres::LossFunction*>(loss), odometry[0], sensor[0]);
    }
    using Cost = FusedNormalCost<3, 6>;
    const auto linearize = [&](size_t k, const double* const* parameters, Cost::Residual* r,
                               Cost::Jacobian* j) {
      if (j == nullptr)
        return LaserResidual(log.intervals[k], &root)(parameters[0], parameters[1], r->data());
      LaserResidual::Linearize(log.intervals[k], root, parameters[0], parameters[1], r, j);
      return true;
    };
    fused.AddResidualBlock(new Cost({3, 3}, log.intervals.size(), linearize, loss, 2), nullptr,
                           odometry[1], sensor[1]);
    const Linearization a = Linearize(&separate);
    const Linearization b = Linearize(&fused);
    if (cost_exact) {
      EXPECT_NEAR(b.cost, a.cost, 1e-10 * a.cost);
    }
    EXPECT_LT((b.gradient - a.gradient).norm(), 1e-9 * a.gradient.norm());
    EXPECT_LT((b.gauss_newton - a.gauss_newton).norm(), 1e-9 * a.gauss_newton.norm());
    // A cost-only evaluation gives the same cost.
    double cost_only = 0.0;
    ASSERT_TRUE(
        fused.Evaluate(ceres::Problem::EvaluateOptions(), &cost_only, nullptr, nullptr, nullptr));
    if (cost_exact) {
      EXPECT_NEAR(cost_only, a.cost, 1e-10 * a.cost);
    }
  }
}

// One evaluation of a fused block: its N + 1 residuals and, when asked, its (N + 1)×6 Jacobian.
struct FusedOutput {
  bool ok = false;
  std::vector<double> residuals = std::vector<double>(7, std::nan(""));
  std::vector<double> jacobians[2] = {std::vector<double>(21, std::nan("")),
                                      std::vector<double>(21, std::nan(""))};
};
FusedOutput EvaluateFused(const ceres::CostFunction& cost, const double* odometry,
                          const double* sensor, bool with_jacobian) {
  FusedOutput out;
  const double* parameters[2] = {odometry, sensor};
  double* jacobians[2] = {out.jacobians[0].data(), out.jacobians[1].data()};
  out.ok = cost.Evaluate(parameters, out.residuals.data(), with_jacobian ? jacobians : nullptr);
  return out;
}
void ExpectSameBits(const std::vector<double>& a, const std::vector<double>& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * a.size()), 0);
}

// A speculating block's cost-only evaluation serves the Jacobian evaluation that follows it at the
// same parameters (no second pass), to the bit what a block without speculation gives; other
// parameters, or a whitening changed and forgotten, are evaluated afresh.
TEST(FusedNormalCostTest, ACostOnlyEvaluationServesTheJacobianThatFollowsIt) {
  const LaserLog log = NoisyLogWithSlips(300, 4);
  Eigen::Matrix3d root = Eigen::Vector3d(1e3, 1e3, 5e2).asDiagonal();
  ceres::CauchyLoss cauchy(3.0);
  using Cost = FusedNormalCost<3, 6>;
  std::atomic<int> jacobian_items{0};
  const auto linearize = [&](size_t k, const double* const* parameters, Cost::Residual* r,
                             Cost::Jacobian* j) {
    if (j == nullptr) {
      LaserResidual::Evaluate(log.intervals[k], root, parameters[0], parameters[1], r);
    } else {
      ++jacobian_items;
      LaserResidual::Linearize(log.intervals[k], root, parameters[0], parameters[1], r, j);
    }
    return true;
  };
  Cost plain({3, 3}, log.intervals.size(), linearize, &cauchy, 2);
  Cost speculating({3, 3}, log.intervals.size(), linearize, &cauchy, 2);
  speculating.set_speculate(true);
  const int n = static_cast<int>(log.intervals.size());
  double odometry[3] = {0.033, 0.031, 0.31};
  const double sensor[3] = {0.1, 0.02, 0.3};
  const auto expect_same = [&](bool with_jacobian, int passes) {
    const FusedOutput want = EvaluateFused(plain, odometry, sensor, with_jacobian);
    jacobian_items = 0;
    const FusedOutput got = EvaluateFused(speculating, odometry, sensor, with_jacobian);
    EXPECT_EQ(jacobian_items.load(), passes * n);
    ASSERT_TRUE(want.ok && got.ok);
    ExpectSameBits(got.residuals, want.residuals);
    for (int b = 0; with_jacobian && b < 2; ++b)
      ExpectSameBits(got.jacobians[b], want.jacobians[b]);
  };
  expect_same(false, 1);  // The cost, with the normal equations formed and kept.
  expect_same(true, 0);   // Taken from the cost-only evaluation.
  expect_same(true, 1);   // Kept for one evaluation only.
  expect_same(false, 1);
  odometry[2] = 0.32;  // Another candidate.
  expect_same(true, 1);
  expect_same(false, 1);
  root(0, 0) = 2e3;  // The owner changes the whitening and says so.
  speculating.ForgetSpeculation();
  expect_same(true, 1);
}

// The fused refinement (the default) ends where the per-interval one does, after the same
// iterations, with the same covariance: Ceres' and the sandwich.
TEST(FusedRefinementTest, EqualsThePerIntervalBlocksPath) {
  const LaserLog log = NoisyLogWithSlips(3000, 21);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  // From the closed form, so that LM has a way to go.
  const LaserCalibration start = result->closed_form.calibration;
  LaserProblem fused({Whitened(log, *result)}, start, LaserRefinementOptions{});
  LaserProblem separate({Whitened(log, *result)}, start, PerInterval());
  ceres::Solver::Summary fused_summary, separate_summary;
  ASSERT_TRUE(fused.Solve(&fused_summary).ok());
  ASSERT_TRUE(separate.Solve(&separate_summary).ok());
  EXPECT_EQ(fused_summary.iterations.size(), separate_summary.iterations.size());
  const StatusOr<CorrectedCovariance<LaserParamMatrix>> covariance = separate.Covariance();
  const StatusOr<CorrectedCovariance<LaserParamMatrix>> fused_covariance = fused.Covariance();
  ASSERT_TRUE(covariance.ok() && fused_covariance.ok());
  const LaserParamVector sigma = covariance->covariance.diagonal().cwiseSqrt();
  const LaserParamVector difference =
      fused.calibration().ToVector() - separate.calibration().ToVector();
  EXPECT_LT(difference.cwiseQuotient(sigma).cwiseAbs().maxCoeff(), 1e-6) << difference.transpose();
  EXPECT_NEAR(fused_covariance->kappa, covariance->kappa, 1e-9);
  EXPECT_LT((fused_covariance->covariance - covariance->covariance).norm(),
            1e-6 * covariance->covariance.norm());
  const StatusOr<CorrectedCovariance<LaserParamMatrix>> sandwich = fused.SandwichCovariance();
  const StatusOr<CorrectedCovariance<LaserParamMatrix>> separate_sandwich =
      separate.SandwichCovariance();
  ASSERT_TRUE(sandwich.ok() && separate_sandwich.ok());
  EXPECT_LT((sandwich->covariance - separate_sandwich->covariance).norm(),
            1e-6 * separate_sandwich->covariance.norm());
}

// Near the optimum (a fraction of σ off, as a later refit round starts), Newton's step of the
// increment-noise pass lands on it; LM, whose Gauss–Newton matrix leaves out Tukey's ρ'' < 0,
// stops a few hundredths of σ short. Without increment covariances the correction is zero.
TEST(FusedRefinementTest, NewtonStepFromNearTheOptimumLandsOnIt) {
  const LaserLog log = NoisyLogWithSlips(3000, 22);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  const LaserParamVector sigma = result->stddev;
  LaserProblem problem({Whitened(log, *result)}, result->estimate, LaserRefinementOptions{});
  problem.Redescend();
  ASSERT_TRUE(problem.Solve().ok());
  const auto newton_step = [&] {
    const StatusOr<LaserProblem::IncrementCorrection> near = problem.IncrementNoiseCorrection({});
    EXPECT_TRUE(near.ok()) << near.message();
    EXPECT_EQ(near->step, LaserParamVector::Zero());
    return near->newton_step;
  };
  const auto step = [&] {
    problem.set_calibration(
        LaserCalibration::FromVector(problem.calibration().ToVector() + newton_step()));
  };
  const LaserParamVector lm_short = newton_step().cwiseQuotient(sigma);
  step();
  step();
  EXPECT_LT(newton_step().cwiseQuotient(sigma).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_GT(lm_short.cwiseAbs().maxCoeff(), 1e-3) << lm_short.transpose();
  const LaserParamVector optimum = problem.calibration().ToVector();
  LaserParamVector offset;
  offset << 0.3, -0.2, 0.25, -0.3, 0.1, 0.2;
  problem.set_calibration(LaserCalibration::FromVector(optimum + offset.cwiseProduct(sigma)));
  step();
  const LaserParamVector landed = problem.calibration().ToVector() - optimum;
  EXPECT_LT(landed.cwiseQuotient(sigma).cwiseAbs().maxCoeff(), 0.01) << landed.transpose();
}

// The sandwich with neighbouring intervals correlated, summed in chunks (each chunk's first
// interval paired with the one before it), equals the same sums taken interval by interval.
TEST(FusedRefinementTest, CorrelatedSandwichEqualsTheSumsInOrder) {
  const LaserLog log = NoisyLogWithSlips(3000, 23);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  const LaserDataset dataset = Whitened(log, *result);
  LaserProblem problem({dataset}, result->estimate, LaserRefinementOptions{});
  problem.Redescend();
  const size_t n = log.intervals.size();
  std::vector<std::vector<Eigen::Matrix3d>> lag_one(1);
  for (size_t k = 0; k + 1 < n; ++k) {
    lag_one[0].push_back(-0.3 * result->noise_sigma[0].cwiseAbs2().asDiagonal().toDenseMatrix());
  }
  const StatusOr<CorrectedCovariance<LaserParamMatrix>> chunked =
      problem.CorrelatedSandwichCovariance(lag_one);
  ASSERT_TRUE(chunked.ok()) << chunked.message();

  const std::unique_ptr<ceres::LossFunction> tukey =
      MakeLossFunction(RobustLoss::kTukey, LaserRefinementOptions{}.redescending_scale);
  const LaserParamVector v = result->estimate.ToVector();
  const SensorMounting mounting(v.data() + 3);
  const Eigen::Matrix3d& root = dataset.sqrt_information;
  SandwichSums<kNumLaserParams> sums;
  Eigen::Matrix<double, 3, kNumLaserParams> j, j_previous;
  Eigen::Vector3d r;
  double weight_previous = 0.0;
  for (size_t k = 0; k < n; ++k) {
    LaserResidual::Linearize(log.intervals[k], root, v.data(), mounting, &r, &j);
    const LossDerivatives rho = EvaluateLoss(tukey.get(), r.squaredNorm());
    sums.Add(j, r, rho);
    if (k > 0) {
      const LaserParamMatrix cross = weight_previous * rho.rho1 * j_previous.transpose() * root *
                                     lag_one[0][k - 1] * root.transpose() * j;
      sums.meat += cross + cross.transpose();
    }
    j_previous = j;
    weight_previous = rho.rho1;
  }
  const StatusOr<CorrectedCovariance<LaserParamMatrix>> in_order =
      SandwichCovariance(sums, 3.0 * n, 3.0 * n - kNumLaserParams);
  ASSERT_TRUE(in_order.ok());
  EXPECT_LT((chunked->covariance - in_order->covariance).norm(),
            1e-10 * in_order->covariance.norm());
  const StatusOr<CorrectedCovariance<LaserParamMatrix>> uncorrelated = problem.SandwichCovariance();
  ASSERT_TRUE(uncorrelated.ok());
  EXPECT_GT((chunked->covariance - uncorrelated->covariance).norm(),
            1e-3 * uncorrelated->covariance.norm());
}

// Without a robust loss and on noise-free data both paths recover the truth exactly.
TEST(FusedRefinementTest, NoiseFreeLeastSquaresRecoversTheTruth) {
  LaserSimOptions sim;
  sim.num_intervals = 400;
  sim.speed_time_constant_s = 0.0;
  sim.scan_noise_sigma.setZero();
  const LaserLog log = SimulateLaserLog(sim);
  const LaserCalibration truth{sim.odometry, sim.base_T_sensor};
  const LaserCalibration nominal{OdometryParams{0.021, 0.021, 0.09}, Pose2d(0.0, 0.0, -1.4)};
  LaserRefinementOptions options;
  options.loss = RobustLoss::kNone;
  for (const LaserRefinementOptions& path : {options, PerInterval(options)}) {
    LaserProblem problem({LaserDataset{&log.intervals, Eigen::Matrix3d::Identity() * 1e3}}, nominal,
                         path);
    ASSERT_TRUE(problem.Solve().ok());
    const LaserParamVector error = problem.calibration().ToVector() - truth.ToVector();
    EXPECT_LT(error.cwiseAbs().maxCoeff(), 1e-9) << error.transpose();
  }
}

// A straight-line log does not determine the parameters: both paths say so from the covariance.
TEST(FusedRefinementTest, UnobservableLogIsSingularOnBothPaths) {
  LaserSimOptions sim;
  sim.num_intervals = 300;
  sim.speed_time_constant_s = 0.0;
  LaserLog log = SimulateLaserLog(sim);
  for (LaserInterval& interval : log.intervals) {
    interval.right_speed = interval.left_speed;  // Straight ahead only.
  }
  // Equal radii: no interval turns the robot, and nothing fixes the sensor's x and y.
  LaserCalibration straight{sim.odometry, sim.base_T_sensor};
  straight.odometry.right_radius_m = straight.odometry.left_radius_m;
  for (const LaserRefinementOptions& path : {LaserRefinementOptions{}, PerInterval()}) {
    LaserProblem problem({LaserDataset{&log.intervals, Eigen::Matrix3d::Identity() * 1e2}},
                         straight, path);
    const StatusOr<CorrectedCovariance<LaserParamMatrix>> covariance = problem.Covariance();
    EXPECT_FALSE(covariance.ok());
    EXPECT_EQ(covariance.code(), StatusCode::kNotObservable) << covariance.message();
  }
}

}  // namespace
}  // namespace calib
