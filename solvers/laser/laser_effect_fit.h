#ifndef CALIB_SOLVERS_LASER_LASER_EFFECT_FIT_H_
#define CALIB_SOLVERS_LASER_LASER_EFFECT_FIT_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/status.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/solvers/laser/laser_refinement.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

// Robust Ceres fits of the laser calibration with candidate effects modelled
// (problems/laser_effect_residual.h), and the per-interval quantities the diagnosis tests on.
namespace calib {

using LaserEffectVector = Eigen::Matrix<double, kNumLaserEffectParams, 1>;

// Columns of the full parameter vector: the six base parameters, then the effect block.
inline constexpr int kNumLaserFullParams = kNumLaserParams + kNumLaserEffectParams;

struct LaserEffectModel {
  std::vector<LaserEffect> effects;  // Modelled (free) effects; the others stay at γ = 0.
  LaserEffectVector gamma = LaserEffectVector::Zero();  // Values (initial values when fitting).
  BoundarySpeedModel boundary = BoundarySpeedModel::kSmooth;
  // Radius change time on the log's clock (start_s); −inf puts every interval after it (the
  // sensitivity of a change before the log), +inf none.
  double change_time_s = std::numeric_limits<double>::infinity();

  bool Has(LaserEffect effect) const;
  // Indices into the full parameter vector of the free parameters: 0..5, then the γ entries of
  // the modelled effects in the order of `effects`.
  std::vector<int> FreeColumns() const;
};

// What all fits of one log share: the intervals, the whitening and the loss.
class LaserEffectData {
 public:
  LaserEffectData(const std::vector<LaserInterval>& intervals,
                  const Eigen::Matrix3d& sqrt_information, const LaserRefinementOptions& options);

  const std::vector<LaserInterval>& intervals() const { return *intervals_; }
  size_t size() const { return intervals_->size(); }
  const Eigen::Matrix3d& sqrt_information() const { return sqrt_information_; }
  // Interval k's whitening: its own when set (e.g. the stamp jitter's Σ_k^{-1/2}), else the
  // shared one.
  const Eigen::Matrix3d& sqrt_information(size_t k) const {
    return interval_sqrt_information_.empty() ? sqrt_information_ : interval_sqrt_information_[k];
  }
  // The shared whitening. Fits made before keep their values.
  void SetSqrtInformation(const Eigen::Matrix3d& root) { sqrt_information_ = root; }
  // One per interval (empty: back to the shared whitening). Fits made before keep their values.
  void SetIntervalSqrtInformation(std::vector<Eigen::Matrix3d> roots) {
    interval_sqrt_information_ = std::move(roots);
  }
  bool has_interval_sqrt_information() const { return !interval_sqrt_information_.empty(); }
  const LaserRefinementOptions& options() const { return options_; }
  // ρ(s), ρ'(s), ρ''(s) of the loss.
  void Loss(double s, double rho[3]) const;
  const ceres::LossFunction* loss() const { return loss_.get(); }
  // Contexts for the model's boundary speeds and change time (changes only the offsets).
  std::vector<LaserEffectContext> Contexts(const LaserEffectModel& model) const;

 private:
  const std::vector<LaserInterval>* intervals_;
  Eigen::Matrix3d sqrt_information_;
  std::vector<Eigen::Matrix3d> interval_sqrt_information_;
  LaserRefinementOptions options_;
  std::unique_ptr<ceres::LossFunction> loss_;
  std::vector<LaserEffectContext> piecewise_;
  std::vector<LaserEffectContext> smooth_;
};

struct LaserEffectFit {
  LaserEffectModel model;  // With the fitted γ.
  LaserCalibration calibration;
  double cost = 0.0;  // ½·Σρ(s_k) over the fitted intervals.
  int iterations = 0;
};

// Fits the six parameters and the model's effects from `initial` and model.gamma, on the
// intervals with (*fit_mask)[k] (all when null).
StatusOr<LaserEffectFit> FitLaserEffects(const LaserEffectData& data, const LaserEffectModel& model,
                                         const LaserCalibration& initial,
                                         const std::vector<bool>* fit_mask = nullptr);

// Per interval at given parameters: whitened residual r_k, the Jacobian with respect to all
// kNumLaserFullParams parameters (with_jacobian), ρ(s_k), ρ'(s_k), ρ''(s_k).
struct LaserEffectEvaluation {
  Eigen::MatrixXd residual;  // N × 3.
  Eigen::MatrixXd jacobian;  // 3N × kNumLaserFullParams (empty without Jacobians).
  Eigen::VectorXd rho0, rho1, rho2;
  // ½·Σρ over the intervals with (*mask)[k] (all when null).
  double Cost(const std::vector<bool>* mask = nullptr) const;
};
LaserEffectEvaluation EvaluateLaserEffects(const LaserEffectData& data,
                                           const LaserEffectModel& model,
                                           const LaserCalibration& calibration,
                                           bool with_jacobian = true);

// Sandwich covariance H⁻¹·B·H⁻¹·n/(n − p) of the parameters in `columns` (indices into the full
// vector), H = Σ J_kᵀ(ρ'·I + 2ρ''·r r ᵀ)J_k, B the long-run covariance of ρ'·J_kᵀr_k (Bartlett
// lags up to hac_lag).
StatusOr<Eigen::MatrixXd> LaserEffectCovariance(const LaserEffectEvaluation& evaluation,
                                                const std::vector<int>& columns, int hac_lag);

// The Jacobian columns `columns` of an evaluation, 3N × columns.size().
Eigen::MatrixXd SelectColumns(const Eigen::MatrixXd& jacobian, const std::vector<int>& columns);

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_EFFECT_FIT_H_
