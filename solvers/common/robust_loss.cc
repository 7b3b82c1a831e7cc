#include <calib/solvers/common/robust_loss.h>

namespace calib {

StatusOr<RobustLoss> ParseRobustLoss(const std::string& name) {
  if (name == "cauchy") return RobustLoss::kCauchy;
  if (name == "huber") return RobustLoss::kHuber;
  if (name == "none") return RobustLoss::kNone;
  return Status::InvalidInput("unknown loss '" + name + "' (expected cauchy, huber or none)");
}

std::string RobustLossName(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::kCauchy:
      return "cauchy";
    case RobustLoss::kHuber:
      return "huber";
    case RobustLoss::kNone:
      return "none";
  }
  return "none";
}

std::unique_ptr<ceres::LossFunction> MakeLossFunction(RobustLoss loss, double scale) {
  switch (loss) {
    case RobustLoss::kCauchy:
      return std::make_unique<ceres::CauchyLoss>(scale);
    case RobustLoss::kHuber:
      return std::make_unique<ceres::HuberLoss>(scale);
    case RobustLoss::kNone:
      return nullptr;
  }
  return nullptr;
}

}  // namespace calib
