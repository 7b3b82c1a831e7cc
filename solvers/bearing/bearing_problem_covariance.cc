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
  // A constant block has no covariance: free τ for the computation.
  const bool was_constant = problem_->IsParameterBlockConstant(time_offset_);
  if (was_constant) problem_->SetParameterBlockVariable(time_offset_);
  const StatusOr<Eigen::MatrixXd> joint = BlockCovariance({calibration_, time_offset_});
  if (was_constant) problem_->SetParameterBlockConstant(time_offset_);
  if (!joint.ok()) return joint.status();
  TimeOffsetCovariance out;
  out.joint = *joint;
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

std::vector<double*> BearingProblem::Latents() const {
  std::vector<double*> latents;
  for (size_t i = 0; i < run_nodes_.size(); ++i) {
    for (size_t k = 0; k < run_nodes_[i]; ++k) {
      latents.push_back(calibration_ + NodeOffset(static_cast<int>(i), static_cast<int>(k)));
    }
  }
  return latents;
}

// ceres::Covariance by sparse QR: a few columns, linear in the nodes for a chain, and on the
// Jacobian itself, where the normal equations square its condition (the odometry is whitened by
// σ down to 1e-7 m against bearings at 1e-2 rad).
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

StatusOr<BearingVarianceComponents> BearingProblem::VarianceComponents(
    const std::vector<std::vector<bool>>& inlier) {
  // Every residual's leverage needs the covariance of every pose and its neighbour's: along the
  // chain (solvers/common/band_arrow_covariance.h), linear in the nodes where ceres::Covariance
  // would be quadratic.
  const StatusOr<BandArrowCovariance> chain =
      ComputeBandArrowCovariance(Latents(), {}, true, options_.num_threads, problem_.get());
  if (chain.code() == StatusCode::kNotObservable) return Status::NotObservable(kSingular);
  CALIB_RETURN_IF_ERROR(chain.status());
  const BandArrowCovariance& cov = *chain;
  BearingVarianceComponents out;
  double all_bearing_redundancy = 0.0;
  for (size_t t = 0; t < bearings_.size(); ++t) {
    const BearingTerm& term = bearings_[t];
    const double h = cov.leverages[term.residual];
    out.total_leverage += h;
    all_bearing_redundancy += 1.0 - h;
    if (!inlier[term.run][term.bearing]) continue;
    const double e = BearingError(term.run, term.node, term.bearing);
    out.bearing_sum_sq_rad2 += e * e;
    out.bearing_redundancy += 1.0 - h;
    ++out.bearing_count;
  }
  for (const OdometryTerm& term : odometry_) {
    const double* blocks[3] = {Node(term.run, term.node - 1), Node(term.run, term.node),
                               calibration_};
    Eigen::Vector3d residual;
    if (!term.cost->Evaluate(blocks, residual.data(), nullptr)) {
      return Status::Internal("an odometry residual could not be evaluated");
    }
    const double h = cov.leverages[term.residual];
    out.total_leverage += h;
    out.odometry_sum_sq += residual.squaredNorm();
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
