#include <calib/solvers/common/robust_loss.h>

#include <cstdio>

namespace calib {

StatusOr<RobustLoss> ParseRobustLoss(const std::string& name) {
  if (name == "cauchy") return RobustLoss::kCauchy;
  if (name == "huber") return RobustLoss::kHuber;
  if (name == "none") return RobustLoss::kNone;
  if (name == "tukey") return RobustLoss::kTukey;
  return Status::InvalidInput("unknown loss '" + name +
                              "' (expected cauchy, huber, tukey or none)");
}

std::string LossStagesName(RobustLoss first, double redescending_scale) {
  std::string text = RobustLossName(first);
  if (first == RobustLoss::kNone || !(redescending_scale > 0.0)) return text;
  char scale[32];
  std::snprintf(scale, sizeof(scale), "%g", redescending_scale);
  return text + ", then tukey (" + scale + ")";
}

std::string RobustLossName(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::kCauchy:
      return "cauchy";
    case RobustLoss::kHuber:
      return "huber";
    case RobustLoss::kNone:
      return "none";
    case RobustLoss::kTukey:
      return "tukey";
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
    case RobustLoss::kTukey:
      return std::make_unique<TukeyBiweightLoss>(scale);
  }
  return nullptr;
}

void TukeyBiweightLoss::Evaluate(double s, double rho[3]) const {
  if (s >= a2_) {
    rho[0] = a2_ / 3.0;
    rho[1] = 0.0;
    rho[2] = 0.0;
    return;
  }
  const double u = 1.0 - s / a2_;
  rho[0] = a2_ / 3.0 * (1.0 - u * u * u);
  rho[1] = u * u;
  rho[2] = -2.0 * u / a2_;
}

}  // namespace calib
