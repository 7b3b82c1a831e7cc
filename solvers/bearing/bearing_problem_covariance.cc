// The covariance side of BearingProblem: loss constants, covariances with κ, leverages.
#include <calib/solvers/bearing/bearing_bundle_adjustment.h>
#include <calib/solvers/common/solver_options.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

namespace calib {
namespace {

constexpr char kSingular[] =
    "the information matrix is singular: the log does not determine φ, ψ, η, δ and ξ (it needs "
    "circular runs at three or more distinct wheel-speed ratios, or runs whose curvature varies, "
    "with the landmark in view)";

// Block (a, b) of a computed covariance, rows × cols.
Eigen::MatrixXd CovarianceBlock(const ceres::Covariance& covariance, const double* a,
                                const double* b, int rows, int cols) {
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> m(rows, cols);
  covariance.GetCovarianceBlock(a, b, m.data());
  return Eigen::MatrixXd(m);
}

}  // namespace

BearingProblem::LossConstants BearingProblem::BearingLossConstants() const {
  LossCorrectionSums sums;
  for (const BearingTermInfo& info : BearingTerms()) {
    sums.Add(info.residual * info.residual, LossDerivatives{info.rho1, info.rho2});
  }
  LossConstants out;
  const std::optional<double> scale = LikelihoodRatioScale(sums);
  if (scale) out.likelihood_ratio_scale = *scale / bearing_redundancy_fraction_;
  out.lambda = CurvatureRatio(sums).value_or(1.0);
  return out;
}

StatusOr<BearingProblem::TimeOffsetCovariance> BearingProblem::CovarianceWithTimeOffset() {
  if (!options_.model_time_offset) return Status::InvalidInput("the problem does not model τ");
  // A constant block has no covariance: free τ while Ceres computes it.
  const bool was_constant = problem_->IsParameterBlockConstant(time_offset_);
  if (was_constant) problem_->SetParameterBlockVariable(time_offset_);
  ceres::Covariance covariance(MakeCovarianceOptions(options_.num_threads));
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
  if (!computed) return Status::NotObservable(kSingular);
  return out;
}

double BearingProblem::LossWeight(double s) const { return EvaluateLoss(loss_.get(), s).rho1; }

double BearingProblem::LossCorrection() const {
  LossCorrectionSums sums;
  for (size_t t = 0; t < bearings_.size(); ++t) {
    const BearingTerm& term = bearings_[t];
    const double e = BearingError(term.run, term.node, term.bearing) * inverse_bearing_sigma_[t];
    sums.Add(e * e, loss_.get());
  }
  // n/Σ(1 − h) passed as 1/fraction.
  const StatusOr<double> kappa = calib::LossCorrection(sums, 1.0, bearing_redundancy_fraction_);
  return kappa.ok() ? *kappa : 1.0;
}

StatusOr<Eigen::MatrixXd> BearingProblem::BlockCovariance(
    const std::vector<const double*>& blocks) const {
  ceres::Covariance covariance(MakeCovarianceOptions(options_.num_threads));
  std::vector<std::pair<const double*, const double*>> pairs;
  int size = 0;
  for (size_t a = 0; a < blocks.size(); ++a) {
    size += problem_->ParameterBlockSize(blocks[a]);
    for (size_t b = a; b < blocks.size(); ++b) pairs.emplace_back(blocks[a], blocks[b]);
  }
  if (!covariance.Compute(pairs, problem_.get())) return Status::NotObservable(kSingular);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> joint(size, size);
  if (!covariance.GetCovarianceMatrix(blocks, joint.data())) {
    return Status::Internal("could not read the covariance from Ceres");
  }
  return Eigen::MatrixXd(joint);
}

StatusOr<CorrectedCovariance<BearingParamMatrix>> BearingProblem::CalibrationCovariance(
    bool loss_correction) const {
  CALIB_ASSIGN_OR_RETURN(const Eigen::MatrixXd cov, BlockCovariance({calibration_}));
  const double kappa = loss_correction ? LossCorrection() : 1.0;
  return CorrectedCovariance<BearingParamMatrix>{BearingParamMatrix(cov * kappa), kappa};
}

double BearingProblem::StartDistance(size_t run_index) const {
  const double* p = Node(run_index, 0);
  return std::hypot(p[0], p[1]);
}

StatusOr<CorrectedCovariance<BearingScaledWithDistanceMatrix>>
BearingProblem::CalibrationCovarianceWithStartDistance(size_t run_index,
                                                       bool loss_correction) const {
  CALIB_ASSIGN_OR_RETURN(const Eigen::MatrixXd cov,
                         BlockCovariance({calibration_, Node(run_index, 0)}));
  const double kappa = loss_correction ? LossCorrection() : 1.0;
  const double* p = Node(run_index, 0);
  const double d = std::hypot(p[0], p[1]);
  Eigen::Matrix<double, kNumBearingParams + 1, kNumBearingParams + 3> g =
      Eigen::Matrix<double, kNumBearingParams + 1, kNumBearingParams + 3>::Zero();
  g.topLeftCorner<kNumBearingParams, kNumBearingParams>().setIdentity();
  g(kNumBearingParams, kNumBearingParams) = p[0] / d;
  g(kNumBearingParams, kNumBearingParams + 1) = p[1] / d;
  return CorrectedCovariance<BearingScaledWithDistanceMatrix>{
      BearingScaledWithDistanceMatrix(g * cov * g.transpose() * kappa), kappa};
}

// Every block pair the leverages need: (c, c), (c, τ), (τ, τ), and per node (pose, pose),
// (pose, c), (pose, τ) and the pair with the previous node.
std::vector<std::pair<const double*, const double*>> BearingProblem::LeveragePairs(
    bool with_offset) const {
  std::vector<std::pair<const double*, const double*>> pairs;
  pairs.emplace_back(calibration_, calibration_);
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
  return pairs;
}

// h = ρ'·J·C·Jᵀ of a bearing with J = ∂r/∂(pose, c[, τ]), as Ceres weighs it in the covariance
// (the leverages then sum to the number of free parameters); its whitened residual in `residual`.
StatusOr<double> BearingProblem::BearingLeverage(const ceres::Covariance& covariance,
                                                 const BearingTerm& term, bool with_offset,
                                                 double* residual) const {
  constexpr int kC = kNumBearingParams;
  const double* pose = Node(term.run, term.node);
  const std::vector<double*> parameters = TermBlocks(term);
  Eigen::Matrix<double, 1, 3, Eigen::RowMajor> j_pose;
  Eigen::Matrix<double, 1, kC, Eigen::RowMajor> j_cal;
  double j_offset = 0.0;
  double* jacobians[3] = {j_pose.data(), j_cal.data(), &j_offset};
  if (!term.cost->Evaluate(parameters.data(), residual, jacobians)) {
    return Status::Internal("a bearing residual could not be evaluated");
  }
  const int size = 3 + kC + (with_offset ? 1 : 0);
  Eigen::RowVectorXd j(size);
  j << j_pose, j_cal, Eigen::RowVectorXd::Constant(size - 3 - kC, j_offset);
  Eigen::MatrixXd c(size, size);
  c.topLeftCorner<3, 3>() = CovarianceBlock(covariance, pose, pose, 3, 3);
  c.block<3, kC>(0, 3) = CovarianceBlock(covariance, pose, calibration_, 3, kC);
  c.block<kC, 3>(3, 0) = c.block<3, kC>(0, 3).transpose();
  c.block<kC, kC>(3, 3) = CovarianceBlock(covariance, calibration_, calibration_, kC, kC);
  if (with_offset) {
    c.block<3, 1>(0, 3 + kC) = CovarianceBlock(covariance, pose, time_offset_, 3, 1);
    c.block<kC, 1>(3, 3 + kC) = CovarianceBlock(covariance, calibration_, time_offset_, kC, 1);
    c.block<1, 3 + kC>(3 + kC, 0) = c.block<3 + kC, 1>(0, 3 + kC).transpose();
    c(3 + kC, 3 + kC) = CovarianceBlock(covariance, time_offset_, time_offset_, 1, 1)(0, 0);
  }
  return LossWeight(*residual * *residual) * (j * c * j.transpose())(0, 0);
}

// tr(J·C·Jᵀ) of an odometry term with J = ∂r/∂(pose0, pose1, c) (it does not depend on τ); its
// squared whitened residual in `squared_norm`.
StatusOr<double> BearingProblem::OdometryLeverage(const ceres::Covariance& covariance,
                                                  const OdometryTerm& term,
                                                  double* squared_norm) const {
  constexpr int kC = kNumBearingParams;
  const double* p0 = Node(term.run, term.node - 1);
  const double* p1 = Node(term.run, term.node);
  const double* parameters[3] = {p0, p1, calibration_};
  Eigen::Vector3d residual;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> j0, j1;
  Eigen::Matrix<double, 3, kC, Eigen::RowMajor> jc;
  double* jacobians[3] = {j0.data(), j1.data(), jc.data()};
  if (!term.cost->Evaluate(parameters, residual.data(), jacobians)) {
    return Status::Internal("an odometry residual could not be evaluated");
  }
  Eigen::Matrix<double, 3, 6 + kC> j;
  j << j0, j1, jc;
  Eigen::Matrix<double, 6 + kC, 6 + kC> c;
  c.block<3, 3>(0, 0) = CovarianceBlock(covariance, p0, p0, 3, 3);
  c.block<3, 3>(3, 3) = CovarianceBlock(covariance, p1, p1, 3, 3);
  c.block<3, 3>(0, 3) = CovarianceBlock(covariance, p0, p1, 3, 3);
  c.block<3, 3>(3, 0) = c.block<3, 3>(0, 3).transpose();
  c.block<3, kC>(0, 6) = CovarianceBlock(covariance, p0, calibration_, 3, kC);
  c.block<3, kC>(3, 6) = CovarianceBlock(covariance, p1, calibration_, 3, kC);
  c.block<kC, 3>(6, 0) = c.block<3, kC>(0, 6).transpose();
  c.block<kC, 3>(6, 3) = c.block<3, kC>(3, 6).transpose();
  c.block<kC, kC>(6, 6) = CovarianceBlock(covariance, calibration_, calibration_, kC, kC);
  *squared_norm = residual.squaredNorm();
  return (j * c * j.transpose()).trace();
}

StatusOr<BearingVarianceComponents> BearingProblem::VarianceComponents(
    const std::vector<std::vector<bool>>& inlier) {
  const bool with_offset = options_.model_time_offset && !options_.fix_time_offset;
  ceres::Covariance covariance(MakeCovarianceOptions(options_.num_threads));
  if (!covariance.Compute(LeveragePairs(with_offset), problem_.get())) {
    return Status::NotObservable(kSingular);
  }
  BearingVarianceComponents out;
  double all_bearing_redundancy = 0.0;
  for (size_t t = 0; t < bearings_.size(); ++t) {
    const BearingTerm& term = bearings_[t];
    double residual = 0.0;
    CALIB_ASSIGN_OR_RETURN(const double h,
                           BearingLeverage(covariance, term, with_offset, &residual));
    out.total_leverage += h;
    all_bearing_redundancy += 1.0 - h;
    if (!inlier[term.run][term.bearing]) continue;
    const double e = residual / inverse_bearing_sigma_[t];
    out.bearing_sum_sq_rad2 += e * e;
    out.bearing_redundancy += 1.0 - h;
    ++out.bearing_count;
  }
  for (const OdometryTerm& term : odometry_) {
    double squared_norm = 0.0;
    CALIB_ASSIGN_OR_RETURN(const double h, OdometryLeverage(covariance, term, &squared_norm));
    out.total_leverage += h;
    out.odometry_sum_sq += squared_norm;
    out.odometry_redundancy += 3.0 - h;
  }
  if (!bearings_.empty() && all_bearing_redundancy > 0.0) {
    bearing_redundancy_fraction_ = all_bearing_redundancy / static_cast<double>(bearings_.size());
  }
  return out;
}

size_t InitialDistanceRun(const BearingLog& log) {
  if (!log.meta.initial_distance) return log.runs.size();
  const int id = log.meta.initial_distance->run;
  return static_cast<size_t>(std::find_if(log.runs.begin(), log.runs.end(),
                                          [&](const BearingRun& r) { return r.id == id; }) -
                             log.runs.begin());
}

StatusOr<BearingEstimateCovariance> EstimateCovariance(const BearingProblem& problem,
                                                       const BearingLog& log,
                                                       const BearingParams& at,
                                                       bool loss_correction) {
  BearingEstimateCovariance out;
  if (!log.meta.initial_distance) {
    CALIB_ASSIGN_OR_RETURN(const CorrectedCovariance<BearingParamMatrix> cov,
                           problem.CalibrationCovariance(loss_correction));
    out.covariance = cov.covariance;
    out.kappa = cov.kappa;
    return out;
  }
  const size_t run = InitialDistanceRun(log);
  CALIB_ASSIGN_OR_RETURN(const CorrectedCovariance<BearingScaledWithDistanceMatrix> joint,
                         problem.CalibrationCovarianceWithStartDistance(run, loss_correction));
  out.covariance = joint.covariance.topLeftCorner<kNumBearingParams, kNumBearingParams>();
  out.kappa = joint.kappa;
  Eigen::Matrix<double, kNumBearingMetricParams, kNumBearingParams + 1> jacobian;
  out.metric =
      BearingMetricFromScaled(at, problem.StartDistance(run), log.meta.initial_distance->meters,
                              log.meta.wheelbase_m, &jacobian);
  out.metric_covariance = jacobian * joint.covariance * jacobian.transpose();
  out.has_metric = true;
  return out;
}

}  // namespace calib
