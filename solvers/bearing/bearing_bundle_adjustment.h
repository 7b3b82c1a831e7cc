#ifndef CALIB_SOLVERS_BEARING_BEARING_BUNDLE_ADJUSTMENT_H_
#define CALIB_SOLVERS_BEARING_BEARING_BUNDLE_ADJUSTMENT_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/bearing/bearing_params.h>
#include <calib/core/se2.h>
#include <calib/core/status.h>
#include <calib/problems/bearing/bearing_observation_residual.h>
#include <calib/solvers/common/band_arrow_covariance.h>
#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/common/robust_loss.h>
#include <ceres/ceres.h>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

// Bundle adjustment of the bearing-only calibration (Martinelli 2009, eqs. 1–6) with Ceres.
//
// Unknowns. The calibration c = (φ, ψ, η, δ, ξ) and, for every run, the robot poses (x, y, θ) in
// the landmark's frame (landmark at the origin) at its nodes: the run's start (its first encoder
// sample, when no bearing is taken there) and every bearing time. Runs are independent
// trajectories sharing c.
//
// Gauge. Bearings are angles and the encoders count wheel rotations, so scaling every length
// (poses, ρ) and the wheel factors δR, δL, δB together changes no measurement: the metric scale
// is unobservable. The problem is posed in the gauge δR ≡ 1, where lengths are in units of δR
// metres and the parameters are exactly the observable set of eq. 5:
//   v = r(Δα_R + δ·Δα_L)/2,  ω = r·ξ(Δα_R − δ·Δα_L),  ρ = 1/(2η)  (in δR metres),  δB = 1/(B·ξ).
// An initial distance D0 of run R's start fixes the scale: with D0' the same distance in the
// gauge, δR = D0/D0', ρ = δR/(2η), δL = δ·δR, δB = δR/(B·ξ). Because D0 carries no information on
// the observable set, this is the maximum-likelihood estimate of the metric set too, and its
// covariance follows from that of (c, D0') (BearingMetricFromScaled).
// Each run can also be turned about the landmark without changing a measurement: its start pose
// is held on the y axis (x ≡ 0), which removes that freedom and nothing else.
//
// Residuals. (a) Odometry terms between consecutive nodes (BearingOdometryResidual): the encoder
// displacement integrated with (δ, ξ) against the displacement between the two pose blocks,
// whitened by the propagated encoder covariance K²·Σ₁ (+ a small floor). (b) Bearing terms
// (BearingObservationResidual) whitened by σβ, under a robust loss.
//
// Circular runs are treated like any trajectory. The closed form further assumes that their
// wheels keep the ratio q exactly; with q itself estimated from the same encoders, its error
// turns the heading by a ramp as large as the random walk the encoders' noise makes, and δ acts
// on the heading as a ramp too, so that premise adds little information (and plugging in the
// estimated q as if exact overstates it: sigmas too small).
namespace calib {

// The noise levels of the model: bearings N(0, σβ²); each encoder increment Δα read with
// variance K²/r·|Δα| (§8.1); and the stamp jitter σ_t of the bearings against the encoder clock:
// a bearing stamped t was taken at t + τ + ε, ε ~ N(0, σ_t²), so to first order its error has
// variance σβ² + σ_t²·(dβ̂/dt)², dβ̂/dt the model's bearing rate there (0: no jitter).
struct BearingNoise {
  double bearing_sigma_rad = 1.0 * M_PI / 180.0;
  double encoder_k = 1e-3;  // K (m^½).
  double bearing_jitter_s = 0.0;
};

struct BearingAdjustmentOptions {
  RobustLoss loss = RobustLoss::kCauchy;
  double loss_scale = 3.0;  // Of the bearing loss, in units of σβ.
  // The last passes, from the optimum under `loss`, use Tukey's biweight at this scale (σβ): a
  // gross bearing then has no influence, where under Cauchy it leaks a fixed bias that a σ
  // shrinking as 1/√N stops covering (20 % of bearings 6–17° off to one side put ψ 13σ off at
  // 10 000 bearings). 0: stay with `loss`; unused without a robust loss.
  double redescending_scale = 6.0;
  int max_iterations = 200;
  int num_threads = 1;
  double initial_trust_region_radius = 1e10;
  // Floor added to each odometry covariance: relative·trace/3 + absolute² (m², rad²), so that a
  // single encoder step (rank 2) or a robot standing still still whitens.
  double covariance_floor_relative = 1e-6;
  double covariance_floor_absolute = 1e-7;
  // Models the bearings' clock offset τ (problems/bearing_time_offset_residual.h): a bearing
  // stamped t was taken at t + τ. τ starts at `time_offset_s` and is estimated unless
  // `fix_time_offset` (then it only adds its sensitivity, for score tests at τ = 0).
  bool model_time_offset = false;
  double time_offset_s = 0.0;
  bool fix_time_offset = false;
  // Per run (log order), per bearing: false leaves that bearing out of the fit (held-out
  // blocks); its pose stays, tied by the odometry. Empty: every bearing is used.
  std::vector<std::vector<bool>> use_bearing;
};

// The nodes of one run: times (s) and, per node, the index of its bearing in the run (−1 for the
// start node when no bearing is taken at the run's first encoder sample).
struct BearingRunNodes {
  int run = 0;
  std::vector<double> t_s;
  std::vector<int> bearing;
};
std::vector<BearingRunNodes> BearingNodes(const BearingLog& log);

// What the variance-component estimate needs: per class the squared residuals and their
// redundancy Σ(1 − leverage) (the residual degrees of freedom that class carries).
struct BearingVarianceComponents {
  double bearing_sum_sq_rad2 = 0.0;  // Σ wrap(β − β̂)² over the inlier bearings.
  double bearing_redundancy = 0.0;   // Σ (1 − h) over the inlier bearings.
  int bearing_count = 0;
  double odometry_sum_sq = 0.0;  // Σ ‖L·e‖² over the odometry terms (whitened at current K).
  double odometry_redundancy = 0.0;  // Σ (3 − tr h) over the odometry terms.
  double total_leverage = 0.0;       // Σ h over every residual = free parameters (a check).
};

// Joint covariance of (φ, ψ, η, δ, ξ, D0') with D0' the distance of a run's start (gauge units).
using BearingScaledWithDistance = Eigen::Matrix<double, kNumBearingParams + 1, 1>;
using BearingScaledWithDistanceMatrix =
    Eigen::Matrix<double, kNumBearingParams + 1, kNumBearingParams + 1>;

// The metric set from the observable set, D0' (gauge units) and D0 (m), with the Jacobian
// ∂(φ, ψ, ρ, δR, δL, δB)/∂(φ, ψ, η, δ, ξ, D0') when `jacobian` is not null.
BearingMetricParams BearingMetricFromScaled(
    const BearingParams& p, double start_distance_gauge, double start_distance_m,
    double wheelbase_m,
    Eigen::Matrix<double, kNumBearingMetricParams, kNumBearingParams + 1>* jacobian = nullptr);

class BearingProblem {
 public:
  // `log` must be valid (ValidateBearingLog) and outlive the problem. `world_T_robot[i][k]` is the
  // initial pose of run i (log order) at node k of BearingNodes(log)[i], in gauge units. Each run
  // is turned about the landmark so that its start lies on the negative y axis.
  BearingProblem(const BearingLog& log, const BearingParams& initial,
                 const std::vector<std::vector<Pose2d>>& world_T_robot, const BearingNoise& noise,
                 const BearingAdjustmentOptions& options = {});
  ~BearingProblem();
  BearingProblem(const BearingProblem&) = delete;
  BearingProblem& operator=(const BearingProblem&) = delete;

  // Solves; the first solve of a redescending problem runs under `loss`, then under Tukey's
  // biweight from that optimum (the summary then holds both stages' iterations).
  Status Solve(ceres::Solver::Summary* summary = nullptr);

  BearingParams params() const;
  std::vector<std::vector<Pose2d>> poses() const;
  const std::vector<BearingRunNodes>& nodes() const { return nodes_; }
  const BearingNoise& noise() const { return noise_; }
  // New noise levels: re-whitens every term (the problem is not rebuilt).
  void SetNoise(const BearingNoise& noise);
  // Recomputes the encoder covariances Σ₁ at the current (δ, ξ) (and, with a stamp jitter, the
  // bearing rates), then re-whitens.
  void Relinearize();
  // dβ̂/dt (rad/s) of every bearing term (BearingTerms' order) at the current estimate: the
  // model's bearing rate at the bearing's time on the encoder clock (t + τ), by autodiff of the
  // time-offset term (problems/bearing/bearing_time_offset_residual.h).
  std::vector<double> BearingRates() const;
  // σ of each bearing term's error (BearingTerms' order): √(σβ² + σ_t²·rate²), σβ without jitter.
  std::vector<double> BearingSigmas() const;

  // wrap(β − β̂) (rad) of every bearing, per run in log order (left-out bearings included).
  std::vector<std::vector<double>> BearingErrors() const;
  // τ (s; 0 unless the options model it).
  double time_offset() const { return time_offset_[0]; }
  // ½Σρ of the problem as it stands, and its gradient with respect to τ (0 without τ).
  double Cost(double* time_offset_gradient = nullptr) const;
  // ∂r/∂τ (whitened, per bearing term in the order of BearingTerms) and the loss's ρ', ρ''.
  struct BearingTermInfo {
    int run = 0;
    int bearing = 0;
    double t_s = 0.0;
    double residual = 0.0;     // Whitened.
    double sensitivity = 0.0;  // ∂r/∂τ (0 without τ).
    double rho1 = 1.0, rho2 = 0.0;
  };
  std::vector<BearingTermInfo> BearingTerms() const;
  // Robust-loss constants of the bearing terms, with the residuals' shrinkage by their leverage
  // counted back (as the covariance's κ): the likelihood-ratio scale mean(ρ'²s)/mean(ρ' + 2ρ''s)
  // (2·Δcost/scale is χ² under the null) and λ = mean(ρ' + 2ρ''s)/mean(ρ').
  struct LossConstants {
    double likelihood_ratio_scale = 1.0;
    double lambda = 1.0;
  };
  LossConstants BearingLossConstants() const;
  // Covariance of (φ, ψ, η, δ, ξ, τ) as ceres::Covariance gives it (no loss correction; the
  // poses eliminated), also while τ is held constant (it is freed for the computation, hence not
  // const). Requires model_time_offset.
  struct TimeOffsetCovariance {
    Eigen::Matrix<double, kNumBearingParams + 1, kNumBearingParams + 1> joint;
  };
  StatusOr<TimeOffsetCovariance> CovarianceWithTimeOffset();
  // The robust loss's weight ρ'(s) for a squared whitened residual s (1 without a loss).
  double LossWeight(double s) const;

  // Covariance of (φ, ψ, η, δ, ξ): ceres::Covariance of the robustified problem (the poses are
  // nuisance: Ceres eliminates them in its factorization of the whole Jacobian). With
  // `loss_correction`, times the correction κ of the bearing terms (LossCorrection), as the laser
  // side does; without it (κ = 1), (JᵀJ)⁻¹ alone, which at the truth with the true noise is the
  // Cramér–Rao bound.
  StatusOr<CorrectedCovariance<BearingParamMatrix>> CalibrationCovariance(
      bool loss_correction = true) const;
  // The same with D0', the distance of run `run_index`'s start node, appended.
  StatusOr<CorrectedCovariance<BearingScaledWithDistanceMatrix>>
  CalibrationCovarianceWithStartDistance(size_t run_index, bool loss_correction = true) const;
  double StartDistance(size_t run_index) const;
  // The robust-loss correction of the bearing terms (solvers/common/robust_covariance.h)
  //   κ = mean(ρ')·mean(ρ'²·s)/mean(ρ' + 2ρ''·s)² · n/Σ(1 − h)
  // (s the squared whitened bearing residuals, n their number, h their leverages as the last
  // VarianceComponents call left them; h = 0 before any): the M-estimator's sandwich H⁻¹·B·H⁻¹,
  // with residuals shrunk by their leverage counted back; 1 for the plain squared loss at the
  // estimated σβ, and when the loss leaves no curvature.
  double LossCorrection() const;

  // Leverages of every residual from the covariance of all blocks (with the loss's weights, as
  // the solution has them), summed per class; bearings with inlier[i][j] false are left out of
  // the bearing class. Also keeps Σ(1 − h) over all bearings for LossCorrection and
  // BearingLossConstants (hence not const).
  StatusOr<BearingVarianceComponents> VarianceComponents(
      const std::vector<std::vector<bool>>& inlier);

  int num_bearings() const { return num_bearings_; }
  int num_odometry_terms() const { return static_cast<int>(odometry_.size()); }

 private:
  struct OdometryTerm {
    int residual = 0;  // Index among the problem's residual blocks (in the order added).
    int run = 0;
    int node = 0;  // Between node − 1 and node.
    const ceres::CostFunction* cost = nullptr;
  };
  struct BearingTerm {
    int residual = 0;
    int run = 0;
    int node = 0;
    int bearing = 0;
    double bearing_rad = 0.0;
    const ceres::CostFunction* cost = nullptr;
  };
  // wrap(β − β̂) of bearing `bearing` of run `run` at node `node`.
  double BearingError(int run, int node, int bearing) const;
  // The parameter blocks of a bearing term.
  std::vector<double*> TermBlocks(const BearingTerm& term) const;

  double* Node(int run, int node) { return calibration_ + NodeOffset(run, node); }
  const double* Node(int run, int node) const { return calibration_ + NodeOffset(run, node); }
  size_t NodeOffset(int run, int node) const {
    return run_offsets_[static_cast<size_t>(run)] + 3 * static_cast<size_t>(node);
  }
  // Σ₁ of one odometry term of run `run`.
  Eigen::Matrix3d UnitCovariance(size_t run, double t0_s, double t1_s, double delta,
                                 double xi) const;
  // Every pose block in chain order (run by run, node by node).
  std::vector<double*> Latents() const;
  StatusOr<Eigen::MatrixXd> BlockCovariance(const std::vector<const double*>& blocks) const;

  const BearingLog* log_;
  std::vector<BearingRunNodes> nodes_;
  BearingAdjustmentOptions options_;
  BearingNoise noise_;
  // Every parameter block in one buffer, in the chain's order (the calibration, τ, then each run's
  // poses): ceres::Covariance orders its columns by the blocks' addresses, and separate heap
  // blocks land in an order that the other threads' allocations change from run to run, and with
  // it the last digits of every covariance.
  std::vector<double> parameters_;
  double* calibration_ = nullptr;
  double* time_offset_ = nullptr;
  std::vector<size_t> run_offsets_;                // Of each run's first pose in parameters_.
  std::vector<size_t> run_nodes_;                  // Each run's number of poses.
  std::vector<Eigen::Matrix3d> unit_covariance_;   // Σ₁ per odometry term.
  std::vector<Eigen::Matrix3d> sqrt_information_;  // Stable addresses (sized once).
  // 1/σ per bearing term (stable addresses: sized once, before the terms hold them), and the
  // bearing rates the jitter weighs them with (computed while a jitter is set).
  std::vector<double> inverse_bearing_sigma_;
  std::vector<double> bearing_rates_;
  bool redescends() const {
    return options_.loss != RobustLoss::kNone && options_.redescending_scale > 0.0;
  }

  std::unique_ptr<ceres::LossFunctionWrapper> loss_;  // Null without a robust loss.
  bool redescended_ = false;
  std::unique_ptr<ceres::Problem> problem_;
  std::vector<OdometryTerm> odometry_;
  std::vector<BearingTerm> bearings_;
  int num_bearings_ = 0;
  double bearing_redundancy_fraction_ = 1.0;  // Σ(1 − h)/n over all bearings (VarianceComponents).
};

// The covariance of an estimate as a calibration reports it: of (φ, ψ, η, δ, ξ), and with an
// initial distance also of the metric set (at `at`, the problem's estimate), with the loss
// correction κ applied (1 without `loss_correction`).
struct BearingEstimateCovariance {
  BearingParamMatrix covariance = BearingParamMatrix::Zero();
  bool has_metric = false;
  BearingMetricParams metric;
  BearingMetricMatrix metric_covariance = BearingMetricMatrix::Zero();
  double kappa = 1.0;
};
StatusOr<BearingEstimateCovariance> EstimateCovariance(const BearingProblem& problem,
                                                       const BearingLog& log,
                                                       const BearingParams& at,
                                                       bool loss_correction = true);

// The index in log.runs of the run the initial distance is given for (log.runs.size() without).
size_t InitialDistanceRun(const BearingLog& log);

// The poses at the nodes of every run obtained by dead reckoning with `params` from a start
// pose given by the landmark's position in the robot frame at the run's start (gauge units).
std::vector<std::vector<Pose2d>> DeadReckonedPoses(
    const BearingLog& log, const BearingParams& params,
    const std::vector<Eigen::Vector2d>& landmark_in_start);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_BUNDLE_ADJUSTMENT_H_
