#ifndef CALIB_SOLVERS_DIAGNOSIS_CONFIRMATION_H_
#define CALIB_SOLVERS_DIAGNOSIS_CONFIRMATION_H_

#include <calib/solvers/diagnosis/finding.h>

#include <functional>
#include <string>
#include <vector>

// The confirmation of an effect that passed its score test: the refit's likelihood ratio at the
// same level AND a lower held-out cost (the model fitted without each block predicts it better).
namespace calib {

// The loss's scale factor of likelihood-ratio statistics from per-sample ρ' and s = ‖r‖²
// (d components each): 2·Δ(½Σρ)/κ is χ² under the null with
//   κ = mean(ρ'²·s)/d / mean(ρ' + 2ρ''·s/d)
// (1 for Gaussian residuals without a robust loss).
double LikelihoodRatioScale(const Eigen::VectorXd& squared_norms, const Eigen::VectorXd& rho1,
                            const Eigen::VectorXd& rho2, int components);

// statistic = max(0, 2·(cost_without − cost_with)/κ), p = survival(statistic) (the null law:
// χ²_dof, a sup over change times, ...), ΔAIC = statistic − 2·dof, ΔBIC = statistic −
// dof·log_n (n the number of residual components).
LikelihoodRatio TestLikelihoodRatio(double cost_without, double cost_with, double kappa, int dof,
                                    double log_n, const std::function<double(double)>& survival);

// Records the refit's evidence in `finding` and returns whether it confirms the effect:
// lr.p_value ≤ finding.holm_level and after.cost < before.cost.
bool Confirm(const LikelihoodRatio& lr, const HeldOutScore& before, const HeldOutScore& after,
             Finding* finding);

// "  NAME: LR x, held-out ±y %[ → adopted]": the progress line of a confirmation.
std::string ConfirmationProgress(const Finding& finding, bool confirmed);

// Why a refitted effect was not adopted, in plain words (for the diagnosis' notes).
std::string RejectionNote(const Finding& finding);

}  // namespace calib

#endif  // CALIB_SOLVERS_DIAGNOSIS_CONFIRMATION_H_
