#ifndef CALIB_SOLVERS_LASER_LASER_REFINEMENT_H_
#define CALIB_SOLVERS_LASER_LASER_REFINEMENT_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/status.h>
#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/common/robust_loss.h>
#include <ceres/ceres.h>

#include <Eigen/Core>
#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

// Maximum-likelihood refinement of the laser–odometry calibration with Ceres
// (Levenberg–Marquardt, robust loss instead of the paper's trimming).
namespace calib {

struct SensorMounting;  // problems/laser/laser_residual.h

struct LaserRefinementOptions {
  RobustLoss loss = RobustLoss::kCauchy;
  // Scale of the loss on the norm of the whitened 3-vector residual: Gaussian inliers
  // (‖r‖² ~ χ²₃, mean 3) keep most of their weight, gross slips lose nearly all of it.
  double loss_scale = 3.0;
  // The last passes, from the optimum under `loss`, use Tukey's biweight at this scale on the
  // whitened norm (an inlier's ‖r‖² ~ χ²₃ passes 6² with probability 1e-7): a gross slip then has
  // no influence, where under Cauchy it leaks a fixed bias that a σ shrinking as 1/√N stops
  // covering on long logs. 0: stay with `loss`; unused without a robust loss.
  double redescending_scale = 6.0;
  int max_iterations = 100;
  int num_threads = 2;
  // Ceres sees one residual block per interval (the reference path, a 3N×6 Jacobian) instead of
  // one block holding every interval's sums (solvers/common/fused_normal_cost.h): the same
  // iterations and estimate to rounding, at a fraction of the time and memory.
  bool per_interval_blocks = false;
};

// One log: its intervals and the square root of its scan-noise information, shared by all its
// intervals or, when `interval_sqrt_information` is given (one per interval), per interval (e.g.
// the timing jitter's Σ_k^{-1/2}, solvers/timing/interval_jitter.h).
struct LaserDataset {
  LaserDataset() = default;
  LaserDataset(const std::vector<LaserInterval>* intervals_in,
               const Eigen::Matrix3d& sqrt_information_in,
               std::vector<Eigen::Matrix3d> interval_sqrt_information_in = {})
      : intervals(intervals_in),
        sqrt_information(sqrt_information_in),
        interval_sqrt_information(std::move(interval_sqrt_information_in)) {}

  const std::vector<LaserInterval>* intervals = nullptr;
  Eigen::Matrix3d sqrt_information = Eigen::Matrix3d::Identity();
  std::vector<Eigen::Matrix3d> interval_sqrt_information;
};

// The Ceres problem over one or more logs sharing the six parameters.
class LaserProblem {
 public:
  LaserProblem(const std::vector<LaserDataset>& datasets, const LaserCalibration& initial,
               const LaserRefinementOptions& options);
  ~LaserProblem();
  LaserProblem(const LaserProblem&) = delete;
  LaserProblem& operator=(const LaserProblem&) = delete;

  // Solves; the first solve of a redescending problem runs under `loss`, then under Tukey's
  // biweight from that optimum (the summary then holds both stages' iterations), telling
  // `after_convex_stage` (may be empty) the first stage's summary in between.
  Status Solve(
      ceres::Solver::Summary* summary = nullptr,
      const std::function<void(const ceres::Solver::Summary&)>& after_convex_stage = nullptr);
  // Whether the next solve runs in two stages (see Solve).
  bool solves_in_stages() const { return redescends() && !redescended_; }
  // Switches to the redescending loss now (for a start already near the robust optimum, e.g. a
  // warm start); no effect when the options ask for none or it is in use.
  void Redescend();
  // The loss the next solve ends with, e.g. "cauchy, then tukey (6)".
  std::string LossDescription() const;
  LaserCalibration calibration() const;
  void set_calibration(const LaserCalibration& calibration);

  size_t num_datasets() const { return datasets_.size(); }
  const Eigen::Matrix3d& sqrt_information(size_t dataset) const {
    return *sqrt_information_[dataset];
  }
  void SetSqrtInformation(size_t dataset, const Eigen::Matrix3d& sqrt_information);
  // Per-interval whitening of a dataset built with one; InvalidInput on a size mismatch or a
  // dataset built with a shared one.
  Status SetIntervalSqrtInformation(size_t dataset, const std::vector<Eigen::Matrix3d>& roots);
  bool has_interval_sqrt_information(size_t dataset) const {
    return !interval_sqrt_information_[dataset].empty();
  }

  // Unwhitened errors e (see LaserResidual) of every interval of a dataset.
  std::vector<Eigen::Vector3d> Errors(size_t dataset) const;
  // Covariance of the six parameters: ceres::Covariance of the robustified problem (whose
  // Jacobian carries the IRLS weights √ρ'), times the loss correction κ with n/(n − 6), n the
  // residual components (solvers/common/robust_covariance.h), and that κ. `errors`, when given,
  // holds Errors(d) of every dataset at the current parameters (saves a pass).
  StatusOr<CorrectedCovariance<LaserParamMatrix>> Covariance(
      const std::vector<std::vector<Eigen::Vector3d>>* errors = nullptr) const;

  // The M-estimator's sandwich H⁻¹·B·H⁻¹·n/(n − 6) from the per-interval Jacobians (κ = 1): one
  // pass over the intervals, for logs where ceres::Covariance takes too long.
  StatusOr<CorrectedCovariance<LaserParamMatrix>> SandwichCovariance() const;

  // The sandwich with the errors of neighbouring intervals correlated: lag_one[d][k] is
  // Cov(e_k, e_{k+1}) of dataset d (unwhitened; empty: none), which adds
  // ρ'_k ρ'_{k+1}·J_kᵀ L_k C_k L_{k+1}ᵀ J_{k+1} and its transpose to B.
  StatusOr<CorrectedCovariance<LaserParamMatrix>> CorrelatedSandwichCovariance(
      const std::vector<std::vector<Eigen::Matrix3d>>& lag_one) const;

  // The errors-in-variables correction of the estimate when each interval's wheel increments
  // (Δφ_l, Δφ_r) carry a zero-mean error of covariance increment_covariance[d][k]: the score
  // ψ_k = ρ'_k·J_kᵀr_k is not linear in Δφ, so E[ψ_k] picks up ½·tr(∂²ψ_k/∂Δφ²·C_k) — the
  // attenuation bias of a noisy regressor. Returns Δp = H⁻¹·Σ_k c_k (H = Σρ'JᵀJ), with c_k that
  // term from second differences along the columns u of C_k's square root:
  // c_k = ½Σ_u [ψ_k(Δφ + u) + ψ_k(Δφ − u) − 2ψ_k(Δφ)]; p + Δp solves the corrected score to
  // first order. Also returns √diag(H⁻¹), the parameters' σ under the model's weights, and from
  // the same pass Newton's step −H_ψ⁻¹·Σψ_k to the robust cost's optimum, H_ψ = Σ[ρ'JᵀJ +
  // 2ρ''(Jᵀr)(Jᵀr)ᵀ] the score's derivative (the sandwich's bread; where it is not positive
  // definite, H instead). LM's Gauss–Newton matrix is H (for ρ'' ≤ 0 Ceres' corrector only scales
  // by √ρ'), which near the optimum converges only linearly (Tukey's ρ'' < 0: H_ψ < H); Newton's
  // step from a fraction of σ away lands on it.
  struct IncrementCorrection {
    LaserParamVector step;
    LaserParamVector stddev;
    LaserParamVector newton_step;
  };
  StatusOr<IncrementCorrection> IncrementNoiseCorrection(
      const std::vector<std::vector<Eigen::Matrix2d>>& increment_covariance) const;

  // The loss's weight ρ'(s) for a squared whitened norm s (1 without a robust loss).
  double LossWeight(double s) const;

 private:
  std::vector<LaserDataset> datasets_;
  // Interval i of the concatenated datasets: dataset d with dataset_begin_[d] ≤ i <
  // dataset_begin_[d + 1].
  std::vector<size_t> dataset_begin_;
  size_t num_intervals() const { return dataset_begin_.back(); }
  size_t DatasetOf(size_t i) const {
    return static_cast<size_t>(std::upper_bound(dataset_begin_.begin(), dataset_begin_.end(), i) -
                               dataset_begin_.begin() - 1);
  }
  // r and J of interval k of dataset d at the current parameters.
  void Linearize(size_t d, size_t k, const SensorMounting& mounting, Eigen::Vector3d* r,
                 Eigen::Matrix<double, 3, 6>* j) const;
  // IncrementNoiseCorrection's sums: H = Σρ'JᵀJ and H_ψ − H = Σ2ρ''(Jᵀr)(Jᵀr)ᵀ (their upper
  // triangles), Σψ_k and Σc_k.
  struct IncrementSums {
    LaserParamMatrix hessian = LaserParamMatrix::Zero();
    LaserParamMatrix curvature = LaserParamMatrix::Zero();
    LaserParamVector gradient = LaserParamVector::Zero();
    LaserParamVector correction = LaserParamVector::Zero();
  };
  // Interval k of dataset d's share of them (c_k when its increments' `covariance` is given).
  void AddIncrementCorrection(size_t d, size_t k, const Eigen::Matrix2d* covariance,
                              const SensorMounting& mounting, IncrementSums* sums) const;
  void AddResidualBlocks(ceres::LossFunction* block_loss);
  void AddFusedBlock(ceres::LossFunction* block_loss);
  // The loss correction's sums over a dataset's intervals, from its errors when given
  // (Errors(dataset) at the current parameters), in parallel chunks.
  LossCorrectionSums LossSums(size_t dataset, const std::vector<Eigen::Vector3d>* errors) const;
  const Eigen::Matrix3d& IntervalSqrtInformation(size_t dataset, size_t k) const {
    return interval_sqrt_information_[dataset].empty() ? *sqrt_information_[dataset]
                                                       : interval_sqrt_information_[dataset][k];
  }

  std::vector<std::unique_ptr<Eigen::Matrix3d>> sqrt_information_;  // Stable addresses.
  // Per dataset, per interval (empty: shared); never resized after construction.
  std::vector<std::vector<Eigen::Matrix3d>> interval_sqrt_information_;
  bool redescends() const {
    return options_.loss != RobustLoss::kNone && options_.redescending_scale > 0.0;
  }

  // The residuals' loss; Redescend() swaps what it wraps.
  std::unique_ptr<ceres::LossFunctionWrapper> loss_;
  // The fused block's ForgetSpeculation (fused_normal_cost.h), when there is one: whenever the
  // whitening or the loss changes.
  std::function<void()> forget_speculation_;
  void ForgetSpeculation() const {
    if (forget_speculation_) forget_speculation_();
  }
  bool redescended_ = false;
  std::unique_ptr<ceres::Problem> problem_;
  LaserRefinementOptions options_;
  double odometry_[3];
  double base_T_sensor_[3];
};

// Robust per-component noise level of errors: 1.4826 × median absolute deviation about the
// median, floored so that noise-free data still give a usable whitening. The components run side
// by side on up to `num_threads` threads (the same figures on any number).
Eigen::Vector3d RobustNoiseSigma(const std::vector<Eigen::Vector3d>& errors, int num_threads = 2);

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_REFINEMENT_H_
