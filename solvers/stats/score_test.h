#ifndef CALIB_SOLVERS_STATS_SCORE_TEST_H_
#define CALIB_SOLVERS_STATS_SCORE_TEST_H_

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <vector>

// Score (Lagrange-multiplier) tests of extra parameters γ at γ = 0 on a robust (M-estimator)
// fit, with the nuisance parameters θ profiled out (Boos 1992, "On generalized score tests").
namespace calib {

// P(χ²_dof > x) for an integer number of degrees of freedom (closed forms).
double ChiSquareSurvival(double x, int dof);

// P(sup_{π ∈ [trim, 1 − trim]} ‖B(π)‖²/(π(1 − π)) > x) for B a dof-dimensional Brownian bridge:
// the null distribution of a sup-score change-point test (Andrews 1993), by the tail
// approximation of Estrella (2003): x^{d/2}·e^{−x/2}/(2^{d/2}Γ(d/2))·[(1 − d/x)·ln λ + 4/x],
// λ = ((1 − trim)/trim)². Capped at 1; conservative on a finite set of candidate times.
double SupChiSquareSurvival(double x, int dof, double trim);

// Long-run covariance of the rows u_k of `contributions` (N × m): Σ_k u_k u_kᵀ plus the
// Bartlett-weighted lags 1..`lag` (Newey–West; positive semi-definite), for scores of intervals
// whose noise is correlated with their neighbours' (consecutive scan matches share a scan).
Eigen::MatrixXd LongRunCovariance(const Eigen::MatrixXd& contributions, int lag);

// Per-sample blocks of a robust fit at its optimum θ̂ (an interval of the laser problem, a
// bearing of the bearing problem): whitened residuals r_k (d each), the Jacobians J_k = ∂r_k/∂θ
// of the nuisance (free) parameters and the loss derivatives ρ'(s_k), ρ''(s_k) at s_k = ‖r_k‖²
// (cost ½Σρ(s_k)).
struct RobustFitBlocks {
  Eigen::MatrixXd residual;  // N × d.
  Eigen::MatrixXd jacobian;  // dN × p; rows d·k..d·k + d − 1 belong to sample k.
  Eigen::VectorXd rho1;      // N.
  Eigen::VectorXd rho2;      // N.
  size_t size() const { return static_cast<size_t>(residual.rows()); }
  Eigen::Index dimension() const { return residual.cols(); }
};

struct ScoreTestResult {
  int dof = 0;
  double statistic = 0.0;  // UᵀV⁻¹U, χ²_dof under γ = 0.
  double p_value = 1.0;
  // False when the data hold (next to) no information on γ beyond what θ already explains:
  // the effect is confounded with θ (or absent from the motion); the test is then meaningless.
  bool identifiable = false;
  // Share of the effect's information the nuisance parameters absorb: 1 − tr(A_γγ⁻¹·I_eff)/dof
  // (0: orthogonal to θ, 1: confounded). NaN when the data carry no information on γ at all.
  double concealment = 0.0;
  Eigen::VectorXd gamma;             // One-step estimate −I_eff⁻¹·U.
  Eigen::MatrixXd gamma_covariance;  // I_eff⁻¹·V·I_eff⁻¹.
  Eigen::MatrixXd absorption;        // B = A_θθ⁻¹A_θγ: how θ̂ absorbs a unit of γ.
  Eigen::VectorXd absorbed;          // B·γ̂: the shift the fit without γ took on.
  // Per interval: u_kᵀV⁻¹U/√statistic, summing to √statistic (the score's share over time).
  Eigen::VectorXd contributions;
};

// With M_k = ρ'_k·I + 2ρ''_k·r_k r_kᵀ (the loss's second-order weight), S_k = ∂r_k/∂γ at γ = 0:
//   A_θθ = Σ J_kᵀM_kJ_k, A_θγ = Σ J_kᵀM_kS_k, A_γγ = Σ S_kᵀM_kS_k, B = A_θθ⁻¹A_θγ,
//   u_k = ρ'_k·(S_k − J_kB)ᵀr_k (the projected score), U = Σu_k,
//   V = long-run covariance of u_k · n/(n − p) (n = d·N residual components),
//   I_eff = A_γγ − A_θγᵀB.
class ScoreTester {
 public:
  // Owns its blocks (move them in when the caller no longer needs them).
  ScoreTester(RobustFitBlocks blocks, int hac_lag);

  // False when A_θθ is singular (the fit itself is not determined).
  bool ok() const { return ok_; }
  const RobustFitBlocks& blocks() const { return blocks_; }

  // `sensitivity`: dN × m, rows d·k.. = S_k.
  ScoreTestResult Test(const Eigen::MatrixXd& sensitivity) const;

  // The effect acting only on intervals k ≥ j (a change at the start of interval j), for every
  // j in [trim·N, (1 − trim)·N]: the sup of the statistics (short-range-independent variance),
  // then the full test at the best j; and where the one-step likelihood ratio peaks.
  struct ChangeScan {
    size_t index = 0;     // Of the sup of the score statistics (the test).
    size_t location = 0;  // Of the largest one-step likelihood ratio UᵀI_eff⁻¹U (the estimate).
    double sup_statistic = 0.0;
    double p_value = 1.0;           // Of the sup, SupChiSquareSurvival.
    std::vector<double> statistic;  // Per j (0 outside the trimmed range).
    ScoreTestResult at_best;
  };
  ChangeScan ScanChange(const Eigen::MatrixXd& sensitivity, double trim) const;

 private:
  RobustFitBlocks blocks_;
  int hac_lag_;
  bool ok_ = false;
  Eigen::MatrixXd a_;                        // A_θθ.
  Eigen::LDLT<Eigen::MatrixXd> a_nuisance_;  // Its factors.
  Eigen::MatrixXd gradients_;                // N × p: g_k = ρ'_k·J_kᵀr_k.
  Eigen::VectorXd gradient_sum_;             // Σ g_k (≈ 0 at the optimum).
  Eigen::MatrixXd gradient_outer_;           // Σ g_k g_kᵀ.
  Eigen::MatrixXd residual_jacobian_;        // N × p: (J_kᵀr_k)ᵀ.
  Eigen::VectorXd row_weights_;              // dN: ρ'_k on each of sample k's rows.
  Eigen::MatrixXd irls_nuisance_;            // Σ ρ'_k·J_kᵀJ_k.
  double small_sample_ = 1.0;                // n/(n − p), n = d·N.
};

}  // namespace calib

#endif  // CALIB_SOLVERS_STATS_SCORE_TEST_H_
