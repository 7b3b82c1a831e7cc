#include <calib/solvers/common/robust_covariance.h>

namespace calib {

LossDerivatives EvaluateLoss(const ceres::LossFunction* loss, double s) {
  if (loss == nullptr) return {};
  double rho[3] = {s, 1.0, 0.0};
  loss->Evaluate(s, rho);
  return {rho[1], rho[2]};
}

std::optional<double> LikelihoodRatioScale(const LossCorrectionSums& sums) {
  if (!(sums.bread > 0.0 && sums.meat > 0.0)) return std::nullopt;
  return sums.meat / sums.bread;
}

std::optional<double> CurvatureRatio(const LossCorrectionSums& sums) {
  if (!(sums.weight > 0.0 && sums.bread > 0.0)) return std::nullopt;
  return sums.bread / sums.weight;
}

StatusOr<double> LossCorrection(const LossCorrectionSums& sums, double components,
                                double redundancy) {
  if (sums.blocks == 0 || !(redundancy > 0.0)) {
    return Status::NotObservable("too few residuals for a covariance");
  }
  if (!(sums.bread > 0.0)) {
    return Status::NotObservable("the robust loss leaves no curvature at the estimate");
  }
  const double n = static_cast<double>(sums.blocks);
  const double mean_weight = sums.weight / n, mean_meat = sums.meat / n,
               mean_bread = sums.bread / n;
  return mean_weight * mean_meat / (mean_bread * mean_bread) * components / redundancy;
}

DominatingCovarianceResult DominatingCovariance(const Eigen::MatrixXd& model,
                                                const Eigen::MatrixXd& sandwich) {
  DominatingCovarianceResult out{model, 1.0};
  const Eigen::LLT<Eigen::MatrixXd> llt(model);
  if (model.rows() == 0 || llt.info() != Eigen::Success || sandwich.rows() != model.rows() ||
      !sandwich.allFinite()) {
    return out;
  }
  const Eigen::MatrixXd l = llt.matrixL();
  const Eigen::MatrixXd whitened =
      llt.matrixL().solve(llt.matrixL().solve(sandwich).transpose().eval());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 *
                                                             (whitened + whitened.transpose()));
  if (eigen.info() != Eigen::Success) return out;
  const Eigen::VectorXd ratio = eigen.eigenvalues().cwiseMax(1.0);
  out.largest_ratio = ratio.maxCoeff();
  const Eigen::MatrixXd lv = l * eigen.eigenvectors();
  out.covariance = lv * ratio.asDiagonal() * lv.transpose();
  return out;
}

}  // namespace calib
