#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/diagnosis/confirmation.h>
#include <calib/solvers/stats/change_point.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace calib {

double HeldOutScore::rms() const {
  return count > 0 ? std::sqrt(sum_sq / (static_cast<double>(components) * count)) : 0.0;
}

double LikelihoodRatioScale(const Eigen::VectorXd& squared_norms, const Eigen::VectorXd& rho1,
                            const Eigen::VectorXd& rho2, int components) {
  LossCorrectionSums sums;
  for (Eigen::Index k = 0; k < squared_norms.size(); ++k) {
    sums.Add(squared_norms(k), LossDerivatives{rho1(k), rho2(k)}, components);
  }
  return LikelihoodRatioScale(sums).value_or(1.0);
}

LikelihoodRatio TestLikelihoodRatio(double cost_without, double cost_with, double kappa, int dof,
                                    double log_n, const std::function<double(double)>& survival) {
  LikelihoodRatio lr;
  lr.statistic = std::max(0.0, 2.0 * (cost_without - cost_with) / kappa);
  lr.p_value = survival(lr.statistic);
  lr.delta_aic = lr.statistic - 2.0 * dof;
  lr.delta_bic = lr.statistic - dof * log_n;
  return lr;
}

bool Confirm(const LikelihoodRatio& lr, const HeldOutScore& before, const HeldOutScore& after,
             Finding* f) {
  f->refitted = true;
  f->lr_statistic = lr.statistic;
  f->lr_p_value = lr.p_value;
  f->delta_aic = lr.delta_aic;
  f->delta_bic = lr.delta_bic;
  f->heldout_cost_before = before.cost;
  f->heldout_cost_after = after.cost;
  f->heldout_rms_before = before.rms();
  f->heldout_rms_after = after.rms();
  f->heldout_reduction = 1.0 - after.cost / before.cost;
  return lr.p_value <= f->holm_level && after.cost < before.cost;
}

std::string ConfirmationProgress(const Finding& f, bool confirmed) {
  char text[256];
  std::snprintf(text, sizeof(text), "  %s: LR %.1f, held-out %+.3f %%%s", f.name.c_str(),
                f.lr_statistic, -100.0 * f.heldout_reduction, confirmed ? " → adopted" : "");
  return text;
}

std::string RejectionNote(const Finding& f) {
  return f.lr_p_value > f.holm_level
             ? f.name + " passed the score test but not the likelihood ratio."
             : f.name + " passed the score test but did not predict the held-out blocks better.";
}

}  // namespace calib
