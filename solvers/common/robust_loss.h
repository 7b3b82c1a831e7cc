#ifndef CALIB_SOLVERS_COMMON_ROBUST_LOSS_H_
#define CALIB_SOLVERS_COMMON_ROBUST_LOSS_H_

#include <calib/core/status.h>
#include <ceres/loss_function.h>

#include <memory>
#include <string>

namespace calib {

// The robust losses every refinement offers (instead of the paper's trimming).
enum class RobustLoss { kCauchy, kHuber, kNone };
StatusOr<RobustLoss> ParseRobustLoss(const std::string& name);  // "cauchy", "huber", "none".
std::string RobustLossName(RobustLoss loss);

// The Ceres loss with the given scale on the whitened residual norm; null for kNone.
std::unique_ptr<ceres::LossFunction> MakeLossFunction(RobustLoss loss, double scale);

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_ROBUST_LOSS_H_
