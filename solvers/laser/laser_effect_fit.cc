#include <calib/problems/laser/laser_effect_columns.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/problems/positive_manifold.h>
#include <calib/solvers/common/fused_normal_cost.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/laser/laser_effect_fit.h>
#include <calib/solvers/stats/score_test.h>
#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace calib {

bool LaserEffectModel::Has(LaserEffect effect) const {
  return std::find(effects.begin(), effects.end(), effect) != effects.end();
}

std::vector<int> LaserEffectModel::FreeColumns() const {
  std::vector<int> columns;
  for (int i = 0; i < kNumLaserParams; ++i) columns.push_back(i);
  for (LaserEffect effect : effects) {
    const LaserEffectInfo& info = EffectInfo(effect);
    for (int i = 0; i < info.size; ++i) columns.push_back(kNumLaserParams + info.offset + i);
  }
  return columns;
}

LaserEffectData::LaserEffectData(const std::vector<LaserInterval>& intervals,
                                 const Eigen::Matrix3d& sqrt_information,
                                 const LaserRefinementOptions& options)
    : intervals_(&intervals), sqrt_information_(sqrt_information), options_(options) {
  loss_ = MakeLossFunction(options.loss, options.loss_scale);
  piecewise_ = BuildLaserEffectContexts(intervals, BoundarySpeedModel::kPiecewiseConstant);
  smooth_ = BuildLaserEffectContexts(intervals, BoundarySpeedModel::kSmooth);
}

void LaserEffectData::Loss(double s, double rho[3]) const {
  rho[0] = s;
  rho[1] = 1.0;
  rho[2] = 0.0;
  if (loss_) loss_->Evaluate(s, rho);
}

std::vector<LaserEffectContext> LaserEffectData::Contexts(const LaserEffectModel& model) const {
  std::vector<LaserEffectContext> contexts =
      model.boundary == BoundarySpeedModel::kSmooth ? smooth_ : piecewise_;
  // With γ_change = 0 the offset changes nothing but which Jacobian columns are non-zero.
  for (LaserEffectContext& context : contexts) {
    context.change_offset_s = model.change_time_s - context.interval->start_s;
  }
  return contexts;
}

namespace {

// The fits run as one fused block over the fitted intervals (see FusedNormalCost). Without
// effects the residual is LaserResidual's (γ = 0 changes nothing in it), linearized in closed
// form; the block then spans (r_l, r_r, b) and the mounting only.
auto BaseLinearization(const LaserEffectData& data, const std::vector<size_t>& fitted) {
  using Cost = FusedNormalCost<3, kNumLaserParams>;
  // Per pass: the mounting's sine and cosine (FusedNormalCost); per interval, the rest.
  return [&data, fitted](const double* const* parameters) {
    return [&data, &fitted, odometry = parameters[0], mounting = SensorMounting(parameters[1])](
               size_t i, Cost::Residual* r, Cost::Jacobian* j) {
      const size_t k = fitted[i];
      const LaserInterval& interval = data.intervals()[k];
      if (j != nullptr) {
        LaserResidual::Linearize(interval, data.sqrt_information(k), odometry, mounting, r, j);
      } else {
        LaserResidual::Evaluate(interval, data.sqrt_information(k), odometry, mounting, r);
      }
      return true;
    };
  };
}

// With effects: LaserEffectResidual by automatic differentiation, the three blocks side by side.
auto EffectLinearization(const LaserEffectData& data,
                         const std::vector<LaserEffectContext>& contexts,
                         const std::vector<size_t>& fitted) {
  using Cost = FusedNormalCost<3, kNumLaserFullParams>;
  return [&data, contexts, fitted](size_t i, const double* const* parameters, Cost::Residual* r,
                                   Cost::Jacobian* j) {
    const size_t k = fitted[i];
    LaserEffectResidual functor(contexts[k], &data.sqrt_information(k));
    if (j == nullptr) return functor(parameters[0], parameters[1], parameters[2], r->data());
    const ceres::AutoDiffCostFunction<LaserEffectResidual, 3, 3, 3, kNumLaserEffectParams> cost(
        &functor, ceres::DO_NOT_TAKE_OWNERSHIP);
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> j_odometry, j_mounting;
    Eigen::Matrix<double, 3, kNumLaserEffectParams, Eigen::RowMajor> j_effects;
    double* jacobians[3] = {j_odometry.data(), j_mounting.data(), j_effects.data()};
    if (!cost.Evaluate(parameters, r->data(), jacobians)) return false;
    *j << j_odometry, j_mounting, j_effects;
    return true;
  };
}

// The residual at γ = 0 and its derivatives in γ (odometry and mounting held constant).
Eigen::Vector3d EffectColumnsAtBase(
    const LaserEffectResidual& functor, const double* odometry, const double* mounting,
    Eigen::Matrix<double, 3, kNumLaserEffectParams, Eigen::RowMajor>* j_effects) {
  using Jet = ceres::Jet<double, kNumLaserEffectParams>;
  const Jet odometry_jet[3] = {Jet(odometry[0]), Jet(odometry[1]), Jet(odometry[2])};
  const Jet mounting_jet[3] = {Jet(mounting[0]), Jet(mounting[1]), Jet(mounting[2])};
  Jet gamma[kNumLaserEffectParams];
  for (int i = 0; i < kNumLaserEffectParams; ++i) gamma[i] = Jet(0.0, i);
  Jet residual[3];
  functor(odometry_jet, mounting_jet, gamma, residual);
  Eigen::Vector3d r;
  for (int i = 0; i < 3; ++i) {
    r(i) = residual[i].a;
    j_effects->row(i) = residual[i].v.transpose();
  }
  return r;
}

}  // namespace

StatusOr<LaserEffectFit> FitLaserEffects(const LaserEffectData& data, const LaserEffectModel& model,
                                         const LaserCalibration& initial,
                                         const std::vector<bool>* fit_mask) {
  const std::vector<LaserEffectContext> contexts = data.Contexts(model);
  double odometry[3] = {initial.odometry.left_radius_m, initial.odometry.right_radius_m,
                        initial.odometry.wheelbase_m};
  double mounting[3] = {initial.base_T_sensor(0), initial.base_T_sensor(1),
                        initial.base_T_sensor(2)};
  LaserEffectVector gamma = LaserEffectVector::Zero();
  std::vector<bool> free(kNumLaserEffectParams, false);
  for (LaserEffect effect : model.effects) {
    const LaserEffectInfo& info = EffectInfo(effect);
    for (int i = 0; i < info.size; ++i) {
      free[info.offset + i] = true;
      gamma(info.offset + i) = model.gamma(info.offset + i);
    }
  }

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = false;
  ceres::Problem problem(problem_options);
  problem.AddParameterBlock(odometry, 3, new PositiveManifold<3>());
  problem.AddParameterBlock(mounting, 3);
  problem.AddParameterBlock(gamma.data(), kNumLaserEffectParams);
  std::vector<int> constant;
  for (int i = 0; i < kNumLaserEffectParams; ++i) {
    if (!free[i]) constant.push_back(i);
  }
  if (static_cast<int>(constant.size()) == kNumLaserEffectParams) {
    problem.SetParameterBlockConstant(gamma.data());
  } else if (!constant.empty()) {
    problem.SetManifold(gamma.data(), new ceres::SubsetManifold(kNumLaserEffectParams, constant));
  }
  std::vector<size_t> fitted;
  for (size_t k = 0; k < contexts.size(); ++k) {
    if (fit_mask == nullptr || (*fit_mask)[k]) fitted.push_back(k);
  }
  if (fitted.empty()) return Status::InvalidInput("no intervals to fit");
  const size_t residuals = fitted.size();
  const int threads = data.options().num_threads;
  if (model.effects.empty()) {
    auto* cost = NewFusedNormalCost<3, kNumLaserParams>(
        {3, 3}, fitted.size(), BaseLinearization(data, fitted), data.loss(), threads);
    // Its whitening and loss stay as they are while it lives; its closed-form Jacobian costs
    // about as much as its residuals (see FusedNormalCost's speculation).
    cost->set_speculate(true);
    problem.AddResidualBlock(cost, nullptr, odometry, mounting);
  } else {
    // Automatic derivatives in 15 variables per interval: two threads pay from a few hundred.
    constexpr size_t kEffectMinChunk = 400;
    // No speculation: these Jacobians cost several times their residuals, and the spare ones
    // cost more than the passes saved (diagnose on data/diagnose/radius_change_and_time_offset:
    // 1.24 → 1.62 s with it).
    problem.AddResidualBlock(
        NewFusedNormalCost<3, kNumLaserFullParams>({3, 3, kNumLaserEffectParams}, fitted.size(),
                                                   EffectLinearization(data, contexts, fitted),
                                                   data.loss(), threads, kEffectMinChunk),
        nullptr, odometry, mounting, gamma.data());
  }

  ceres::Solver::Summary summary;
  CALIB_RETURN_IF_ERROR(Solve(LaserEffectFitSettings(residuals, data.options().max_iterations, 1),
                              "the refit with effects", &problem, &summary));
  if (!(odometry[0] > 0.0 && odometry[1] > 0.0 && odometry[2] > 0.0)) {
    return Status::NotConverged(
        "the refit with effects drove a radius or the wheelbase non-positive");
  }
  LaserEffectFit fit;
  fit.model = model;
  fit.model.gamma = gamma;
  fit.calibration.odometry = OdometryParams{odometry[0], odometry[1], odometry[2]};
  fit.calibration.base_T_sensor = Pose2d(mounting[0], mounting[1], WrapAngle(mounting[2]));
  fit.cost = summary.final_cost;
  fit.iterations = static_cast<int>(summary.iterations.size());
  return fit;
}

double LaserEffectEvaluation::Cost(const std::vector<bool>* mask) const {
  double sum = 0.0;
  for (Eigen::Index k = 0; k < rho0.size(); ++k) {
    if (mask == nullptr || (*mask)[k]) sum += rho0(k);
  }
  return 0.5 * sum;
}

LaserEffectEvaluation EvaluateLaserEffects(const LaserEffectData& data,
                                           const LaserEffectModel& model,
                                           const LaserCalibration& calibration,
                                           bool with_jacobian) {
  const std::vector<LaserEffectContext> contexts = data.Contexts(model);
  const size_t n = contexts.size();
  LaserEffectEvaluation evaluation;
  evaluation.residual.resize(n, 3);
  if (with_jacobian) evaluation.jacobian.resize(3 * n, kNumLaserFullParams);
  evaluation.rho0.resize(n);
  evaluation.rho1.resize(n);
  evaluation.rho2.resize(n);
  const double odometry[3] = {calibration.odometry.left_radius_m,
                              calibration.odometry.right_radius_m,
                              calibration.odometry.wheelbase_m};
  const double mounting[3] = {calibration.base_T_sensor(0), calibration.base_T_sensor(1),
                              calibration.base_T_sensor(2)};
  const double* parameters[3] = {odometry, mounting, model.gamma.data()};
  // At γ = 0 the residual is LaserResidual's in (r_l, r_r, b, mounting) whatever their values,
  // so its six columns are that residual's closed form; only the effects' nine columns need
  // automatic derivatives, in γ alone (a third fewer directions than all fifteen).
  const bool at_base = with_jacobian && (model.gamma.array() == 0.0).all();
  const SensorMounting sensor_mounting(mounting);
  // Each interval's automatic differentiation costs microseconds: in chunks on the problem's
  // threads.
  constexpr size_t kMinChunk = 256;
  ParallelChunks(n, data.options().num_threads, kMinChunk, [&](size_t, size_t begin, size_t end) {
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> j_odometry, j_mounting;
    Eigen::Matrix<double, 3, kNumLaserEffectParams, Eigen::RowMajor> j_effects;
    double* jacobians[3] = {j_odometry.data(), j_mounting.data(), j_effects.data()};
    for (size_t k = begin; k < end; ++k) {
      LaserEffectResidual functor(contexts[k], &data.sqrt_information(k));
      Eigen::Vector3d r;
      if (at_base) {
        Eigen::Matrix<double, 3, kNumLaserParams> j_base;
        if (!EffectColumnsAtZero(contexts[k], data.sqrt_information(k), odometry, sensor_mounting,
                                 &r, &j_base, &j_effects)) {
          Eigen::Vector3d r_base;
          LaserResidual::Linearize(*contexts[k].interval, data.sqrt_information(k), odometry,
                                   sensor_mounting, &r_base, &j_base);
          r = EffectColumnsAtBase(functor, odometry, mounting, &j_effects);
        }
        evaluation.jacobian.block<3, kNumLaserParams>(3 * k, 0) = j_base;
        evaluation.jacobian.block<3, kNumLaserEffectParams>(3 * k, kNumLaserParams) = j_effects;
      } else {
        const ceres::AutoDiffCostFunction<LaserEffectResidual, 3, 3, 3, kNumLaserEffectParams> cost(
            &functor, ceres::DO_NOT_TAKE_OWNERSHIP);
        cost.Evaluate(parameters, r.data(), with_jacobian ? jacobians : nullptr);
        if (with_jacobian) {
          evaluation.jacobian.block<3, 3>(3 * k, 0) = j_odometry;
          evaluation.jacobian.block<3, 3>(3 * k, 3) = j_mounting;
          evaluation.jacobian.block<3, kNumLaserEffectParams>(3 * k, kNumLaserParams) = j_effects;
        }
      }
      evaluation.residual.row(k) = r.transpose();
      double rho[3];
      data.Loss(r.squaredNorm(), rho);
      evaluation.rho0(k) = rho[0];
      evaluation.rho1(k) = rho[1];
      evaluation.rho2(k) = rho[2];
    }
  });
  return evaluation;
}

Eigen::MatrixXd SelectColumns(const Eigen::MatrixXd& jacobian, const std::vector<int>& columns) {
  Eigen::MatrixXd selected(jacobian.rows(), static_cast<Eigen::Index>(columns.size()));
  for (size_t i = 0; i < columns.size(); ++i) selected.col(i) = jacobian.col(columns[i]);
  return selected;
}

StatusOr<Eigen::MatrixXd> LaserEffectCovariance(const LaserEffectEvaluation& evaluation,
                                                const std::vector<int>& columns, int hac_lag) {
  const Eigen::Index n = evaluation.residual.rows();
  const Eigen::Index p = static_cast<Eigen::Index>(columns.size());
  if (3 * n <= p) return Status::NotObservable("too few intervals for a covariance");
  const Eigen::MatrixXd j = SelectColumns(evaluation.jacobian, columns);
  SandwichSums<Eigen::Dynamic> sums(p);
  Eigen::MatrixXd scores(n, p);
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Vector3d r = evaluation.residual.row(k).transpose();
    const Eigen::VectorXd jr = sums.AddBread(
        j.middleRows(3 * k, 3), r, LossDerivatives{evaluation.rho1(k), evaluation.rho2(k)});
    scores.row(k) = evaluation.rho1(k) * jr.transpose();
  }
  const double components = 3.0 * n;
  const StatusOr<CorrectedCovariance<Eigen::MatrixXd>> covariance = SandwichCovariance(
      sums.bread, LongRunCovariance(scores, hac_lag), components, components - p);
  if (!covariance.ok()) {
    return Status::NotObservable(
        "the information matrix is singular: the log does not determine the "
        "parameters with these effects");
  }
  return covariance->covariance;
}

}  // namespace calib
