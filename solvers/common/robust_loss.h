#ifndef CALIB_SOLVERS_COMMON_ROBUST_LOSS_H_
#define CALIB_SOLVERS_COMMON_ROBUST_LOSS_H_

#include <calib/core/status.h>
#include <ceres/loss_function.h>

#include <memory>
#include <string>

namespace calib {

// The robust losses every refinement offers (instead of the paper's trimming). Tukey's biweight
// redescends: a residual beyond its scale has no influence at all, where Cauchy's still pulls with
// a²/‖r‖ (a fixed bias that a σ shrinking as 1/√N stops covering on long logs).
enum class RobustLoss { kCauchy, kHuber, kNone, kTukey };
// "cauchy", "huber", "none", "tukey".
StatusOr<RobustLoss> ParseRobustLoss(const std::string& name);
std::string RobustLossName(RobustLoss loss);
// The losses a fit ends with: `first`, then Tukey's biweight at `redescending_scale` when that is
// positive and `first` robust, e.g. "cauchy, then tukey (6)".
std::string LossStagesName(RobustLoss first, double redescending_scale);

// The Ceres loss with the given scale on the whitened residual norm; null for kNone.
std::unique_ptr<ceres::LossFunction> MakeLossFunction(RobustLoss loss, double scale);

// Tukey's biweight with ρ'(0) = 1 like the other losses (ceres::TukeyLoss has ρ'(0) = ½):
// ρ(s) = a²/3·(1 − (1 − s/a²)³) for s ≤ a², a²/3 beyond; ρ'(s) = (1 − s/a²)².
class TukeyBiweightLoss : public ceres::LossFunction {
 public:
  explicit TukeyBiweightLoss(double scale) : a2_(scale * scale) {}
  void Evaluate(double s, double rho[3]) const override;

 private:
  double a2_;
};

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_ROBUST_LOSS_H_
