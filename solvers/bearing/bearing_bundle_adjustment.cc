#include <calib/solvers/bearing/bearing_bundle_adjustment.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>

#include <calib/core/whitening.h>
#include <calib/problems/bearing/bearing_odometry_residual.h>
#include <calib/problems/bearing/bearing_time_offset_residual.h>
#include <calib/problems/positive_manifold.h>
#include <calib/solvers/bearing/martinelli_closed_form.h>

namespace calib {
namespace {

constexpr char kSingular[] =
    "the information matrix is singular: the log does not determine φ, ψ, η, δ and ξ (it needs "
    "circular runs at three or more distinct wheel-speed ratios, or runs whose curvature varies, "
    "with the landmark in view)";

}  // namespace

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
  loss_ = MakeLossFunction(options.loss, options.loss_scale);
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = false;
  problem_ = std::make_unique<ceres::Problem>(problem_options);

  const BearingParamVector c = ToVector(initial);
  for (int i = 0; i < kNumBearingParams; ++i) calibration_[i] = c(i);
  // η, δ, ξ stay positive (η < 0 is the same sensor with φ + π; δ, ξ < 0 are not wheels).
  problem_->AddParameterBlock(
      calibration_, kNumBearingParams,
      new ceres::ProductManifold<ceres::EuclideanManifold<2>, PositiveManifold<3>>());

  // Poses, each run turned about the landmark so that its start is on the negative y axis.
  size_t num_intervals = 0;
  poses_.resize(log.runs.size());
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const std::vector<Pose2d>& given = world_T_robot[i];
    const double turn = -0.5 * M_PI - std::atan2(given.front()(1), given.front()(0));
    const double ct = std::cos(turn), st = std::sin(turn);
    for (const Pose2d& p : given) {
      poses_[i].push_back({ct * p(0) - st * p(1), st * p(0) + ct * p(1), p(2) + turn});
    }
    poses_[i].front()[0] = 0.0;
    num_intervals += given.size() - 1;
  }
  unit_covariance_.reserve(num_intervals);
  sqrt_information_.assign(num_intervals, Eigen::Matrix3d::Identity());

  time_offset_[0] = options.model_time_offset ? options.time_offset_s : 0.0;
  if (options.model_time_offset) {
    problem_->AddParameterBlock(time_offset_, 1);
    if (options.fix_time_offset) problem_->SetParameterBlockConstant(time_offset_);
  }
  const double r = log.meta.wheel_radius_m;
  const double b = log.meta.wheelbase_m;
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
        odometry_.push_back(OdometryTerm{static_cast<int>(i), static_cast<int>(k), cost});
      }
      const int j = nodes.bearing[k];
      const bool used = j >= 0 && (options.use_bearing.empty() || options.use_bearing[i][j]);
      if (used) {
        const double beta = run.bearings[j].bearing_rad;
        ceres::CostFunction* cost = nullptr;
        if (options.model_time_offset) {
          cost = BearingTimeOffsetResidual::Create(beta, nodes.t_s[k], &odometry, r, b,
                                                   &inverse_bearing_sigma_);
          problem_->AddResidualBlock(cost, loss_.get(), Node(i, k), calibration_, time_offset_);
        } else {
          cost = BearingObservationResidual::Create(beta, &inverse_bearing_sigma_);
          problem_->AddResidualBlock(cost, loss_.get(), Node(i, k), calibration_);
        }
        bearings_.push_back(
            BearingTerm{static_cast<int>(i), static_cast<int>(k), nodes.bearing[k], beta, cost});
        ++num_bearings_;
      }
    }
  }
  SetNoise(noise);
}

BearingProblem::~BearingProblem() = default;

void BearingProblem::SetNoise(const BearingNoise& noise) {
  noise_ = noise;
  inverse_bearing_sigma_ = 1.0 / noise.bearing_sigma_rad;
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
  SetNoise(noise_);
}

Status BearingProblem::Solve(ceres::Solver::Summary* summary) {
  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options_.max_iterations;
  // The stiff odometry chains make the normal equations badly conditioned: a small initial
  // radius damps the soft modes (the runs' shapes) for a dozen iterations. Start near
  // Gauss–Newton; LM still backs off when a step fails.
  solver_options.initial_trust_region_radius = options_.initial_trust_region_radius;
  solver_options.max_trust_region_radius = 1e16;
  solver_options.num_threads = options_.num_threads;
  // The cost is about half a unit per bearing; stop once an iteration gains far less than a
  // hundredth of a sigma's worth.
  solver_options.function_tolerance = 1e-10;
  solver_options.gradient_tolerance = 1e-14;
  solver_options.parameter_tolerance = 1e-12;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary local_summary;
  ceres::Solve(solver_options, problem_.get(), &local_summary);
  if (summary != nullptr) *summary = local_summary;
  if (local_summary.termination_type == ceres::FAILURE ||
      !std::isfinite(local_summary.final_cost)) {
    return Status::Error("the bundle adjustment failed: " + local_summary.message);
  }
  for (double v : calibration_) {
    if (!std::isfinite(v)) return Status::Error("the bundle adjustment diverged");
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
  std::vector<std::vector<Pose2d>> out(poses_.size());
  for (size_t i = 0; i < poses_.size(); ++i) {
    for (const auto& p : poses_[i]) out[i].push_back(Pose2d(p[0], p[1], WrapAngle(p[2])));
  }
  return out;
}

double BearingProblem::BearingError(int run, int node, int bearing) const {
  const double beta = log_->runs[run].bearings[bearing].bearing_rad;
  if (!options_.model_time_offset) {
    return BearingObservationResidual::Error(beta, Node(run, node), calibration_);
  }
  const BearingTimeOffsetResidual model(beta, nodes_[run].t_s[node], &log_->runs[run].odometry,
                                        log_->meta.wheel_radius_m, log_->meta.wheelbase_m,
                                        &inverse_bearing_sigma_);
  return model.Error(Node(run, node), calibration_, time_offset_);
}

std::vector<double*> BearingProblem::TermBlocks(const BearingTerm& term) const {
  std::vector<double*> blocks = {const_cast<double*>(Node(term.run, term.node)),
                                 const_cast<double*>(calibration_)};
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

void BearingProblem::LossConstants(double* likelihood_ratio_scale, double* lambda) const {
  double weight = 0.0, meat = 0.0, bread = 0.0;
  for (const BearingTermInfo& info : BearingTerms()) {
    const double s = info.residual * info.residual;
    weight += info.rho1;
    meat += info.rho1 * info.rho1 * s;
    bread += info.rho1 + 2.0 * info.rho2 * s;
  }
  *likelihood_ratio_scale =
      bread > 0.0 && meat > 0.0 ? meat / bread / bearing_redundancy_fraction_ : 1.0;
  *lambda = weight > 0.0 && bread > 0.0 ? bread / weight : 1.0;
}

StatusOr<BearingProblem::TimeOffsetCovariance> BearingProblem::CovarianceWithTimeOffset() const {
  if (!options_.model_time_offset) return Status::Error("the problem does not model τ");
  // A constant block has no covariance: free τ while Ceres computes it.
  const bool was_constant = problem_->IsParameterBlockConstant(time_offset_);
  if (was_constant) problem_->SetParameterBlockVariable(time_offset_);
  ceres::Covariance::Options covariance_options;
  covariance_options.num_threads = options_.num_threads;
  covariance_options.algorithm_type = ceres::SPARSE_QR;
  covariance_options.apply_loss_function = true;
  ceres::Covariance covariance(covariance_options);
  std::vector<std::pair<const double*, const double*>> pairs = {
      {calibration_, calibration_}, {calibration_, time_offset_}, {time_offset_, time_offset_}};
  const bool computed = covariance.Compute(pairs, problem_.get());
  TimeOffsetCovariance out;
  if (computed) {
    Eigen::Matrix<double, kNumBearingParams + 1, kNumBearingParams + 1, Eigen::RowMajor> joint;
    covariance.GetCovarianceMatrix({calibration_, time_offset_}, joint.data());
    out.joint = joint;
  }
  if (was_constant) problem_->SetParameterBlockConstant(time_offset_);
  if (!computed) return Status::Error(kSingular);
  return out;
}

double BearingProblem::LossWeight(double s) const {
  if (!loss_) return 1.0;
  double rho[3];
  loss_->Evaluate(s, rho);
  return rho[1];
}

void BearingProblem::UpdateKappa() const {
  double sum_weight = 0.0, sum_meat = 0.0, sum_bread = 0.0;
  for (const BearingTerm& term : bearings_) {
    const double e = BearingError(term.run, term.node, term.bearing) * inverse_bearing_sigma_;
    const double s = e * e;
    double rho[3] = {s, 1.0, 0.0};
    if (loss_) loss_->Evaluate(s, rho);
    sum_weight += rho[1];
    sum_meat += rho[1] * rho[1] * s;
    sum_bread += rho[1] + 2.0 * rho[2] * s;
  }
  const double n = static_cast<double>(std::max<size_t>(1, bearings_.size()));
  covariance_scale_ = sum_bread > 0.0
                          ? (sum_weight / n) * (sum_meat / n) /
                                ((sum_bread / n) * (sum_bread / n)) / bearing_redundancy_fraction_
                          : 1.0;
}

StatusOr<Eigen::MatrixXd> BearingProblem::BlockCovariance(
    const std::vector<const double*>& blocks) const {
  ceres::Covariance::Options covariance_options;
  covariance_options.num_threads = options_.num_threads;
  covariance_options.algorithm_type = ceres::SPARSE_QR;
  covariance_options.apply_loss_function = true;
  ceres::Covariance covariance(covariance_options);
  std::vector<std::pair<const double*, const double*>> pairs;
  int size = 0;
  for (size_t a = 0; a < blocks.size(); ++a) {
    size += problem_->ParameterBlockSize(blocks[a]);
    for (size_t b = a; b < blocks.size(); ++b) pairs.emplace_back(blocks[a], blocks[b]);
  }
  if (!covariance.Compute(pairs, problem_.get())) return Status::Error(kSingular);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> joint(size, size);
  if (!covariance.GetCovarianceMatrix(blocks, joint.data())) {
    return Status::Error("could not read the covariance from Ceres");
  }
  return Eigen::MatrixXd(joint);
}

StatusOr<BearingParamMatrix> BearingProblem::Covariance(bool loss_correction) const {
  StatusOr<Eigen::MatrixXd> cov = BlockCovariance({calibration_});
  if (!cov.ok()) return cov.status();
  covariance_scale_ = 1.0;
  if (loss_correction) UpdateKappa();
  return BearingParamMatrix(*cov * covariance_scale_);
}

double BearingProblem::StartDistance(size_t run_index) const {
  const double* p = Node(run_index, 0);
  return std::hypot(p[0], p[1]);
}

StatusOr<BearingScaledWithDistanceMatrix> BearingProblem::CovarianceWithStartDistance(
    size_t run_index, bool loss_correction) const {
  StatusOr<Eigen::MatrixXd> cov = BlockCovariance({calibration_, Node(run_index, 0)});
  if (!cov.ok()) return cov.status();
  covariance_scale_ = 1.0;
  if (loss_correction) UpdateKappa();
  const double* p = Node(run_index, 0);
  const double d = std::hypot(p[0], p[1]);
  Eigen::Matrix<double, kNumBearingParams + 1, kNumBearingParams + 3> g =
      Eigen::Matrix<double, kNumBearingParams + 1, kNumBearingParams + 3>::Zero();
  g.topLeftCorner<kNumBearingParams, kNumBearingParams>().setIdentity();
  g(kNumBearingParams, kNumBearingParams) = p[0] / d;
  g(kNumBearingParams, kNumBearingParams + 1) = p[1] / d;
  return BearingScaledWithDistanceMatrix(g * *cov * g.transpose() * covariance_scale_);
}

StatusOr<BearingVarianceComponents> BearingProblem::VarianceComponents(
    const std::vector<std::vector<bool>>& inlier) const {
  ceres::Covariance::Options covariance_options;
  covariance_options.num_threads = options_.num_threads;
  covariance_options.algorithm_type = ceres::SPARSE_QR;
  covariance_options.apply_loss_function = true;
  ceres::Covariance covariance(covariance_options);
  std::vector<std::pair<const double*, const double*>> pairs;
  pairs.emplace_back(calibration_, calibration_);
  const bool with_offset = options_.model_time_offset && !options_.fix_time_offset;
  if (with_offset) {
    pairs.emplace_back(calibration_, time_offset_);
    pairs.emplace_back(time_offset_, time_offset_);
  }
  for (size_t i = 0; i < poses_.size(); ++i) {
    for (size_t k = 0; k < poses_[i].size(); ++k) {
      pairs.emplace_back(Node(i, k), Node(i, k));
      pairs.emplace_back(Node(i, k), calibration_);
      if (with_offset) pairs.emplace_back(Node(i, k), time_offset_);
      if (k > 0) pairs.emplace_back(Node(i, k - 1), Node(i, k));
    }
  }
  if (!covariance.Compute(pairs, problem_.get())) return Status::Error(kSingular);
  constexpr int kC = kNumBearingParams;
  Eigen::Matrix<double, kC, kC, Eigen::RowMajor> cc;
  covariance.GetCovarianceBlock(calibration_, calibration_, cc.data());
  const auto block = [&](const double* a, const double* b, int rows, int cols) {
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(rows, cols);
    covariance.GetCovarianceBlock(a, b, m.data());
    return Eigen::MatrixXd(m);
  };

  BearingVarianceComponents out;
  double all_bearing_redundancy = 0.0;
  // Bearings: h = ρ'·J·C·Jᵀ with J = ∂r/∂(pose, c), as Ceres weighs them in the covariance (the
  // leverages then sum to the number of free parameters).
  for (const BearingTerm& term : bearings_) {
    const double* pose = Node(term.run, term.node);
    const std::vector<double*> parameters = TermBlocks(term);
    double residual = 0.0;
    Eigen::Matrix<double, 1, 3, Eigen::RowMajor> j_pose;
    Eigen::Matrix<double, 1, kC, Eigen::RowMajor> j_cal;
    double j_offset = 0.0;
    double* jacobians[3] = {j_pose.data(), j_cal.data(), &j_offset};
    if (!term.cost->Evaluate(parameters.data(), &residual, jacobians)) {
      return Status::Error("a bearing residual could not be evaluated");
    }
    // Blocks (pose, c[, τ]): J·C·Jᵀ.
    const int size = 3 + kC + (with_offset ? 1 : 0);
    Eigen::RowVectorXd j(size);
    j << j_pose, j_cal, Eigen::RowVectorXd::Constant(size - 3 - kC, j_offset);
    Eigen::MatrixXd c(size, size);
    c.topLeftCorner<3, 3>() = block(pose, pose, 3, 3);
    c.block<3, kC>(0, 3) = block(pose, calibration_, 3, kC);
    c.block<kC, 3>(3, 0) = c.block<3, kC>(0, 3).transpose();
    c.block<kC, kC>(3, 3) = cc;
    if (with_offset) {
      c.block<3, 1>(0, 3 + kC) = block(pose, time_offset_, 3, 1);
      c.block<kC, 1>(3, 3 + kC) = block(calibration_, time_offset_, kC, 1);
      c.block<1, 3 + kC>(3 + kC, 0) = c.block<3 + kC, 1>(0, 3 + kC).transpose();
      c(3 + kC, 3 + kC) = block(time_offset_, time_offset_, 1, 1)(0, 0);
    }
    const double h = LossWeight(residual * residual) * (j * c * j.transpose())(0, 0);
    out.total_leverage += h;
    all_bearing_redundancy += 1.0 - h;
    if (!inlier[term.run][term.bearing]) continue;
    const double e = residual / inverse_bearing_sigma_;
    out.bearing_sum_sq_rad2 += e * e;
    out.bearing_redundancy += 1.0 - h;
    ++out.bearing_count;
  }
  // Odometry terms: tr(J·C·Jᵀ) with J = ∂r/∂(pose0, pose1, c).
  for (const OdometryTerm& term : odometry_) {
    const double* p0 = Node(term.run, term.node - 1);
    const double* p1 = Node(term.run, term.node);
    const double* parameters[3] = {p0, p1, calibration_};
    // (The odometry terms do not depend on τ.)
    Eigen::Vector3d residual;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> j0, j1;
    Eigen::Matrix<double, 3, kC, Eigen::RowMajor> jc;
    double* jacobians[3] = {j0.data(), j1.data(), jc.data()};
    if (!term.cost->Evaluate(parameters, residual.data(), jacobians)) {
      return Status::Error("an odometry residual could not be evaluated");
    }
    Eigen::Matrix<double, 3, 6 + kC> j;
    j << j0, j1, jc;
    Eigen::Matrix<double, 6 + kC, 6 + kC> c;
    c.block<3, 3>(0, 0) = block(p0, p0, 3, 3);
    c.block<3, 3>(3, 3) = block(p1, p1, 3, 3);
    c.block<3, 3>(0, 3) = block(p0, p1, 3, 3);
    c.block<3, 3>(3, 0) = c.block<3, 3>(0, 3).transpose();
    c.block<3, kC>(0, 6) = block(p0, calibration_, 3, kC);
    c.block<3, kC>(3, 6) = block(p1, calibration_, 3, kC);
    c.block<kC, 3>(6, 0) = c.block<3, kC>(0, 6).transpose();
    c.block<kC, 3>(6, 3) = c.block<3, kC>(3, 6).transpose();
    c.block<kC, kC>(6, 6) = cc;
    const double h = (j * c * j.transpose()).trace();
    out.total_leverage += h;
    out.odometry_sum_sq += residual.squaredNorm();
    out.odometry_redundancy += 3.0 - h;
  }
  if (!bearings_.empty() && all_bearing_redundancy > 0.0) {
    bearing_redundancy_fraction_ = all_bearing_redundancy / static_cast<double>(bearings_.size());
  }
  return out;
}

}  // namespace calib
