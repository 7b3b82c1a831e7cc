#include <calib/core/whitening.h>
#include <calib/problems/bearing/bearing_odometry_residual.h>
#include <calib/problems/bearing/bearing_time_offset_residual.h>
#include <calib/problems/positive_manifold.h>
#include <calib/solvers/bearing/bearing_bundle_adjustment.h>
#include <calib/solvers/bearing/martinelli_closed_form.h>
#include <calib/solvers/common/solver_options.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

namespace calib {

std::vector<BearingRunNodes> BearingNodes(const BearingLog& log) {
  std::vector<BearingRunNodes> all;
  for (const BearingRun& run : log.runs) {
    BearingRunNodes nodes;
    nodes.run = run.id;
    const double t0 = run.odometry.empty() ? 0.0 : run.odometry.front().t_s;
    if (run.bearings.empty() ||
        run.bearings.front().t_s > t0 + 1e-9 * std::max(1.0, std::abs(t0))) {
      nodes.t_s.push_back(t0);
      nodes.bearing.push_back(-1);
    }
    for (size_t j = 0; j < run.bearings.size(); ++j) {
      nodes.t_s.push_back(run.bearings[j].t_s);
      nodes.bearing.push_back(static_cast<int>(j));
    }
    all.push_back(std::move(nodes));
  }
  return all;
}

BearingMetricParams BearingMetricFromScaled(
    const BearingParams& p, double start_distance_gauge, double start_distance_m,
    double wheelbase_m,
    Eigen::Matrix<double, kNumBearingMetricParams, kNumBearingParams + 1>* jacobian) {
  const double delta_r = start_distance_m / start_distance_gauge;
  const BearingMetricParams m = MetricParams(p, delta_r / (2.0 * p.eta_per_m), wheelbase_m);
  if (jacobian != nullptr) {
    const double d = start_distance_gauge;
    jacobian->setZero();
    (*jacobian)(0, kBearingPhi) = 1.0;
    (*jacobian)(1, kBearingPsi) = 1.0;
    (*jacobian)(2, kBearingEta) = -m.rho_m / p.eta_per_m;  // ρ = D0/(2η·D0').
    (*jacobian)(2, kNumBearingParams) = -m.rho_m / d;
    (*jacobian)(3, kNumBearingParams) = -m.delta_r / d;  // δR = D0/D0'.
    (*jacobian)(4, kBearingDelta) = m.delta_r;           // δL = δ·δR.
    (*jacobian)(4, kNumBearingParams) = -m.delta_l / d;
    (*jacobian)(5, kBearingXi) = -m.delta_b / p.xi_per_m;  // δB = δR/(B·ξ).
    (*jacobian)(5, kNumBearingParams) = -m.delta_b / d;
  }
  return m;
}

std::vector<std::vector<Pose2d>> DeadReckonedPoses(
    const BearingLog& log, const BearingParams& params,
    const std::vector<Eigen::Vector2d>& landmark_in_start) {
  const std::vector<BearingRunNodes> nodes = BearingNodes(log);
  const double r = log.meta.wheel_radius_m;
  const double b = log.meta.wheelbase_m;
  const double delta_b = 1.0 / (b * params.xi_per_m);
  std::vector<std::vector<Pose2d>> poses(log.runs.size());
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const std::vector<EncoderSample>& odometry = log.runs[i].odometry;
    const Eigen::Vector2d& landmark = landmark_in_start[i];
    // The start on the negative y axis, turned so that the landmark (the origin) lies at
    // `landmark` in its frame.
    const double distance = landmark.norm();
    Pose2d pose(0.0, -distance, 0.5 * M_PI - std::atan2(landmark.y(), landmark.x()));
    double t = odometry.front().t_s;
    for (double t_node : nodes[i].t_s) {
      pose =
          Compose(pose, IntegrateEncoders(odometry, t, t_node, r, b, 1.0, params.delta, delta_b));
      t = t_node;
      poses[i].push_back(pose);
    }
  }
  return poses;
}

BearingProblem::BearingProblem(const BearingLog& log, const BearingParams& initial,
                               const std::vector<std::vector<Pose2d>>& world_T_robot,
                               const BearingNoise& noise, const BearingAdjustmentOptions& options)
    : log_(&log), nodes_(BearingNodes(log)), options_(options), noise_(noise) {
  if (options.loss != RobustLoss::kNone) {
    loss_ = std::make_unique<ceres::LossFunctionWrapper>(
        MakeLossFunction(options.loss, options.loss_scale).release(), ceres::TAKE_OWNERSHIP);
  }
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = false;
  problem_ = std::make_unique<ceres::Problem>(problem_options);

  size_t num_nodes = 0;
  for (const std::vector<Pose2d>& given : world_T_robot) {
    run_offsets_.push_back(kNumBearingParams + 1 + 3 * num_nodes);
    run_nodes_.push_back(given.size());
    num_nodes += given.size();
  }
  parameters_.assign(kNumBearingParams + 1 + 3 * num_nodes, 0.0);
  calibration_ = parameters_.data();
  time_offset_ = calibration_ + kNumBearingParams;
  const BearingParamVector c = ToVector(initial);
  for (int i = 0; i < kNumBearingParams; ++i) calibration_[i] = c(i);
  // η, δ, ξ stay positive (η < 0 is the same sensor with φ + π; δ, ξ < 0 are not wheels).
  problem_->AddParameterBlock(
      calibration_, kNumBearingParams,
      new ceres::ProductManifold<ceres::EuclideanManifold<2>, PositiveManifold<3>>());

  // Poses, each run turned about the landmark so that its start is on the negative y axis.
  size_t num_intervals = 0;
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const std::vector<Pose2d>& given = world_T_robot[i];
    const double turn = -0.5 * M_PI - std::atan2(given.front()(1), given.front()(0));
    const double ct = std::cos(turn), st = std::sin(turn);
    for (size_t k = 0; k < given.size(); ++k) {
      const Pose2d& p = given[k];
      double* node = Node(static_cast<int>(i), static_cast<int>(k));
      node[0] = ct * p(0) - st * p(1);
      node[1] = st * p(0) + ct * p(1);
      node[2] = p(2) + turn;
    }
    Node(static_cast<int>(i), 0)[0] = 0.0;
    num_intervals += given.size() - 1;
  }
  unit_covariance_.reserve(num_intervals);
  sqrt_information_.assign(num_intervals, Eigen::Matrix3d::Identity());

  size_t num_used = 0;
  for (size_t i = 0; i < log.runs.size(); ++i) {
    for (int j : nodes_[i].bearing) {
      num_used += j >= 0 && (options.use_bearing.empty() || options.use_bearing[i][j]);
    }
  }
  inverse_bearing_sigma_.assign(num_used, 1.0);

  time_offset_[0] = options.model_time_offset ? options.time_offset_s : 0.0;
  if (options.model_time_offset) {
    problem_->AddParameterBlock(time_offset_, 1);
    if (options.fix_time_offset) problem_->SetParameterBlockConstant(time_offset_);
  }
  const double r = log.meta.wheel_radius_m;
  const double b = log.meta.wheelbase_m;
  int num_residuals = 0;
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const BearingRun& run = log.runs[i];
    const BearingRunNodes& nodes = nodes_[i];
    const std::vector<EncoderSample>& odometry = run.odometry;
    for (size_t k = 0; k < nodes.t_s.size(); ++k) {
      problem_->AddParameterBlock(Node(i, k), 3);
      if (k == 0) problem_->SetManifold(Node(i, k), new ceres::SubsetManifold(3, {0}));
      if (k > 0) {
        unit_covariance_.push_back(
            UnitCovariance(i, nodes.t_s[k - 1], nodes.t_s[k], initial.delta, initial.xi_per_m));
        ceres::CostFunction* cost = BearingOdometryResidual::Create(
            &odometry, nodes.t_s[k - 1], nodes.t_s[k], r, b, &sqrt_information_[odometry_.size()]);
        problem_->AddResidualBlock(cost, nullptr, Node(i, k - 1), Node(i, k), calibration_);
        odometry_.push_back(
            OdometryTerm{num_residuals++, static_cast<int>(i), static_cast<int>(k), cost});
      }
      const int j = nodes.bearing[k];
      const bool used = j >= 0 && (options.use_bearing.empty() || options.use_bearing[i][j]);
      if (used) {
        const double beta = run.bearings[j].bearing_rad;
        ceres::CostFunction* cost = nullptr;
        if (options.model_time_offset) {
          cost = BearingTimeOffsetResidual::Create(beta, nodes.t_s[k], &odometry, r, b,
                                                   &inverse_bearing_sigma_[bearings_.size()]);
          problem_->AddResidualBlock(cost, loss_.get(), Node(i, k), calibration_, time_offset_);
        } else {
          cost =
              BearingObservationResidual::Create(beta, &inverse_bearing_sigma_[bearings_.size()]);
          problem_->AddResidualBlock(cost, loss_.get(), Node(i, k), calibration_);
        }
        bearings_.push_back(BearingTerm{num_residuals++, static_cast<int>(i), static_cast<int>(k),
                                        nodes.bearing[k], beta, cost});
        ++num_bearings_;
      }
    }
  }
  SetNoise(noise);
}

BearingProblem::~BearingProblem() = default;

void BearingProblem::SetNoise(const BearingNoise& noise) {
  noise_ = noise;
  if (noise.bearing_jitter_s > 0.0 && bearing_rates_.size() != bearings_.size()) {
    bearing_rates_ = BearingRates();
  }
  const std::vector<double> sigmas = BearingSigmas();
  for (size_t t = 0; t < bearings_.size(); ++t) inverse_bearing_sigma_[t] = 1.0 / sigmas[t];
  const double k2 = noise.encoder_k * noise.encoder_k;
  const double absolute = options_.covariance_floor_absolute * options_.covariance_floor_absolute;
  for (size_t t = 0; t < unit_covariance_.size(); ++t) {
    const Eigen::Matrix3d cov = k2 * unit_covariance_[t];
    const double floor = options_.covariance_floor_relative * cov.trace() / 3.0 + absolute;
    sqrt_information_[t] = SqrtInformation<3>(cov + floor * Eigen::Matrix3d::Identity());
  }
}

Eigen::Matrix3d BearingProblem::UnitCovariance(size_t run, double t0_s, double t1_s, double delta,
                                               double xi) const {
  const double r = log_->meta.wheel_radius_m;
  const double b = log_->meta.wheelbase_m;
  return EncoderDisplacementCovariance(log_->runs[run].odometry, t0_s, t1_s, r, b, 1.0, delta,
                                       1.0 / (b * xi), 1.0, 1.0);
}

void BearingProblem::Relinearize() {
  const BearingParams p = params();
  for (size_t t = 0; t < odometry_.size(); ++t) {
    const OdometryTerm& term = odometry_[t];
    const BearingRunNodes& nodes = nodes_[term.run];
    unit_covariance_[t] = UnitCovariance(term.run, nodes.t_s[term.node - 1], nodes.t_s[term.node],
                                         p.delta, p.xi_per_m);
  }
  if (noise_.bearing_jitter_s > 0.0) bearing_rates_ = BearingRates();
  SetNoise(noise_);
}

std::vector<double> BearingProblem::BearingRates() const {
  // r = wrap(β − β̂(t + τ))/σ with σ = 1: ∂r/∂τ = −dβ̂/dt.
  const double one = 1.0;
  const double tau = time_offset_[0];
  std::vector<double> rates;
  rates.reserve(bearings_.size());
  for (const BearingTerm& term : bearings_) {
    const ceres::AutoDiffCostFunction<BearingTimeOffsetResidual, 1, 3, kNumBearingParams, 1> cost(
        new BearingTimeOffsetResidual(term.bearing_rad, nodes_[term.run].t_s[term.node],
                                      &log_->runs[term.run].odometry, log_->meta.wheel_radius_m,
                                      log_->meta.wheelbase_m, &one));
    const double* blocks[3] = {Node(term.run, term.node), calibration_, &tau};
    double residual = 0.0, d_tau = 0.0;
    double* jacobians[3] = {nullptr, nullptr, &d_tau};
    cost.Evaluate(blocks, &residual, jacobians);
    rates.push_back(-d_tau);
  }
  return rates;
}

std::vector<double> BearingProblem::BearingSigmas() const {
  const double sigma = noise_.bearing_sigma_rad;
  const double jitter = noise_.bearing_jitter_s;
  std::vector<double> sigmas(bearings_.size(), sigma);
  if (!(jitter > 0.0)) return sigmas;  // Exactly σβ: the plain model, bit for bit.
  for (size_t t = 0; t < bearings_.size(); ++t) {
    sigmas[t] = std::sqrt(sigma * sigma + jitter * jitter * bearing_rates_[t] * bearing_rates_[t]);
  }
  return sigmas;
}

Status BearingProblem::Solve(ceres::Solver::Summary* summary) {
  const auto solve = [&](ceres::Solver::Summary* stage) {
    return calib::Solve(BearingAdjustmentSettings(options_.max_iterations, options_.num_threads,
                                                  options_.initial_trust_region_radius),
                        "the bundle adjustment", problem_.get(), stage);
  };
  std::function<void()> redescend;
  if (redescends() && !redescended_) {
    redescend = [this] {
      loss_->Reset(MakeLossFunction(RobustLoss::kTukey, options_.redescending_scale).release(),
                   ceres::TAKE_OWNERSHIP);
      redescended_ = true;
    };
  }
  CALIB_RETURN_IF_ERROR(SolveInStages(solve, redescend, summary));
  for (int i = 0; i < kNumBearingParams; ++i) {
    if (!std::isfinite(calibration_[i])) {
      return Status::NotConverged("the bundle adjustment diverged");
    }
  }
  return Status::Ok();
}

BearingParams BearingProblem::params() const {
  BearingParamVector v;
  for (int i = 0; i < kNumBearingParams; ++i) v(i) = calibration_[i];
  BearingParams p = BearingParamsFromVector(v);
  p.phi_rad = WrapAngle(p.phi_rad);
  p.psi_rad = WrapAngle(p.psi_rad);
  return p;
}

std::vector<std::vector<Pose2d>> BearingProblem::poses() const {
  std::vector<std::vector<Pose2d>> out(run_nodes_.size());
  for (size_t i = 0; i < run_nodes_.size(); ++i) {
    for (size_t k = 0; k < run_nodes_[i]; ++k) {
      const double* p = Node(static_cast<int>(i), static_cast<int>(k));
      out[i].push_back(Pose2d(p[0], p[1], WrapAngle(p[2])));
    }
  }
  return out;
}

double BearingProblem::BearingError(int run, int node, int bearing) const {
  const double beta = log_->runs[run].bearings[bearing].bearing_rad;
  if (!options_.model_time_offset) {
    return BearingObservationResidual::Error(beta, Node(run, node), calibration_);
  }
  const double one = 1.0;
  const BearingTimeOffsetResidual model(beta, nodes_[run].t_s[node], &log_->runs[run].odometry,
                                        log_->meta.wheel_radius_m, log_->meta.wheelbase_m, &one);
  return model.Error(Node(run, node), calibration_, time_offset_);
}

std::vector<double*> BearingProblem::TermBlocks(const BearingTerm& term) const {
  std::vector<double*> blocks = {const_cast<double*>(Node(term.run, term.node)), calibration_};
  if (options_.model_time_offset) blocks.push_back(time_offset_);
  return blocks;
}

std::vector<std::vector<double>> BearingProblem::BearingErrors() const {
  std::vector<std::vector<double>> errors(log_->runs.size());
  for (size_t i = 0; i < log_->runs.size(); ++i) {
    errors[i].assign(log_->runs[i].bearings.size(), 0.0);
    for (size_t k = 0; k < nodes_[i].t_s.size(); ++k) {
      const int j = nodes_[i].bearing[k];
      if (j >= 0) errors[i][j] = BearingError(static_cast<int>(i), static_cast<int>(k), j);
    }
  }
  return errors;
}

double BearingProblem::Cost(double* time_offset_gradient) const {
  double cost = 0.0;
  problem_->Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
  if (time_offset_gradient != nullptr) {
    // ∂(½Σρ)/∂τ = Σ ρ'·r·∂r/∂τ (also when τ is held constant, as for a score test).
    double gradient = 0.0;
    for (const BearingTermInfo& info : BearingTerms()) {
      gradient += info.rho1 * info.residual * info.sensitivity;
    }
    *time_offset_gradient = gradient;
  }
  return cost;
}

std::vector<BearingProblem::BearingTermInfo> BearingProblem::BearingTerms() const {
  std::vector<BearingTermInfo> out;
  out.reserve(bearings_.size());
  for (const BearingTerm& term : bearings_) {
    BearingTermInfo info;
    info.run = term.run;
    info.bearing = term.bearing;
    info.t_s = nodes_[term.run].t_s[term.node];
    const std::vector<double*> blocks = TermBlocks(term);
    double jacobian_offset = 0.0;
    std::vector<double*> jacobians(blocks.size(), nullptr);
    if (options_.model_time_offset) jacobians.back() = &jacobian_offset;
    term.cost->Evaluate(blocks.data(), &info.residual, jacobians.data());
    info.sensitivity = jacobian_offset;
    double rho[3] = {0.0, 1.0, 0.0};
    if (loss_) loss_->Evaluate(info.residual * info.residual, rho);
    info.rho1 = rho[1];
    info.rho2 = rho[2];
    out.push_back(info);
  }
  return out;
}

}  // namespace calib
