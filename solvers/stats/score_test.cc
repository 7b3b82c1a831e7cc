#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/stats/score_test.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace calib {
namespace {

// Relative efficient information below which γ counts as confounded with θ: exact confounding
// leaves ~1e-12 after the subtraction, a weakly identified effect orders of magnitude more.
constexpr double kConfoundedInformation = 1e-6;

// Full-bread (M_k) and IRLS (ρ'_k·I in place of M_k) cross products over all samples.
struct CrossProducts {
  Eigen::MatrixXd a_tg, a_gg;        // A_θγ, A_γγ.
  Eigen::MatrixXd w_tt, w_tg, w_gg;  // Their IRLS versions, and Σ ρ'_k·J_kᵀJ_k.
  Eigen::MatrixXd raw_scores;        // N × m: ρ'_k·S_kᵀr_k.
};

// Row k = r_kᵀM_k, M_k sample k's d rows of `m`.
Eigen::MatrixXd ResidualProducts(const RobustFitBlocks& blocks, const Eigen::MatrixXd& m) {
  const Eigen::Index d = blocks.dimension();
  Eigen::MatrixXd out(blocks.size(), m.cols());
  for (size_t k = 0; k < blocks.size(); ++k) {
    out.row(k).noalias() = blocks.residual.row(k) * m.middleRows(d * k, d);
  }
  return out;
}

// The sums as products of the stacked matrices (no per-sample temporaries): with W the row
// weights ρ'_k and C = diag(2ρ''_k), W_θγ = JᵀWS, W_γγ = SᵀWS, A_θγ = W_θγ + (Jr)ᵀC(Sr),
// A_γγ = W_γγ + (Sr)ᵀC(Sr), where row k of Jr and Sr is r_kᵀJ_k and r_kᵀS_k.
CrossProducts AccumulateCrossProducts(const RobustFitBlocks& blocks,
                                      const Eigen::MatrixXd& residual_jacobian,
                                      const Eigen::VectorXd& row_weights,
                                      const Eigen::MatrixXd& irls_nuisance,
                                      const Eigen::MatrixXd& sensitivity) {
  CrossProducts c;
  const Eigen::MatrixXd sr = ResidualProducts(blocks, sensitivity);
  const Eigen::MatrixXd weighted = row_weights.asDiagonal() * sensitivity;
  c.w_tt = irls_nuisance;
  c.w_tg.noalias() = blocks.jacobian.transpose() * weighted;
  c.w_gg.noalias() = sensitivity.transpose() * weighted;
  const Eigen::MatrixXd curved = (2.0 * blocks.rho2).asDiagonal() * sr;
  c.a_tg = c.w_tg;
  c.a_tg.noalias() += residual_jacobian.transpose() * curved;
  c.a_gg = c.w_gg;
  c.a_gg.noalias() += sr.transpose() * curved;
  c.raw_scores = blocks.rho1.asDiagonal() * sr;
  return c;
}

// Concealment and identifiability in the IRLS metric (positive weights) into `result`; returns
// the efficient information in that metric, W_γγ − W_θγᵀW_θθ⁻¹W_θγ.
Eigen::MatrixXd IrlsConcealment(const CrossProducts& c, ScoreTestResult* result) {
  const Eigen::Index m = c.w_gg.cols();
  const Eigen::LDLT<Eigen::MatrixXd> w_nuisance(c.w_tt);
  const Eigen::MatrixXd w_eff = c.w_gg - c.w_tg.transpose() * w_nuisance.solve(c.w_tg);
  const Eigen::LLT<Eigen::MatrixXd> w_llt(c.w_gg);
  if (c.w_gg.trace() > 0.0 && w_llt.info() == Eigen::Success) {
    const Eigen::MatrixXd l_inv = w_llt.matrixL().solve(Eigen::MatrixXd::Identity(m, m));
    const Eigen::MatrixXd relative = l_inv * w_eff * l_inv.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 *
                                                               (relative + relative.transpose()));
    result->concealment = 1.0 - relative.trace() / m;
    result->identifiable = eigen.eigenvalues().minCoeff() > kConfoundedInformation;
  } else {
    result->concealment = std::numeric_limits<double>::quiet_NaN();
  }
  return w_eff;
}

bool PositiveDefinite(const Eigen::LDLT<Eigen::MatrixXd>& ldlt) {
  return ldlt.info() == Eigen::Success && (ldlt.vectorD().array() > 0.0).all();
}

}  // namespace

double ChiSquareSurvival(double x, int dof) {
  if (dof <= 0) return 0.0;
  if (!(x > 0.0)) return 1.0;
  if (!std::isfinite(x)) return 0.0;
  const double half = 0.5 * x;
  double sum = 0.0;
  if (dof % 2 == 0) {
    // e^{−x/2}·Σ_{i<d/2} (x/2)^i/i!, each term in logs so that neither factor overflows.
    for (int i = 0; i < dof / 2; ++i) {
      sum += std::exp(-half + i * std::log(half) - std::lgamma(i + 1.0));
    }
  } else {
    // erfc(√(x/2)) + e^{−x/2}·Σ_{i≤(d−3)/2} (x/2)^{i+1/2}/Γ(i + 3/2).
    sum = std::erfc(std::sqrt(half));
    for (int i = 0; i <= (dof - 3) / 2; ++i) {
      sum += std::exp(-half + (i + 0.5) * std::log(half) - std::lgamma(i + 1.5));
    }
  }
  return std::clamp(sum, 0.0, 1.0);
}

double SupChiSquareSurvival(double x, int dof, double trim) {
  if (dof <= 0) return 0.0;
  const double single = ChiSquareSurvival(x, dof);
  if (!(x > dof)) return 1.0;  // The tail approximation holds only beyond the mean.
  trim = std::clamp(trim, 1e-6, 0.499);
  const double log_lambda = 2.0 * std::log((1.0 - trim) / trim);
  const double d = dof;
  const double log_density =
      0.5 * d * std::log(x) - 0.5 * x - 0.5 * d * std::log(2.0) - std::lgamma(0.5 * d);
  const double bracket = (1.0 - d / x) * log_lambda + 4.0 / x;
  const double p = std::exp(log_density) * bracket;
  return std::clamp(std::max(p, single), 0.0, 1.0);
}

Eigen::MatrixXd LongRunCovariance(const Eigen::MatrixXd& contributions, int lag) {
  const Eigen::Index n = contributions.rows();
  Eigen::MatrixXd v = contributions.transpose() * contributions;
  for (int l = 1; l <= lag && l < n; ++l) {
    const Eigen::MatrixXd gamma =
        contributions.bottomRows(n - l).transpose() * contributions.topRows(n - l);
    v += (1.0 - l / (lag + 1.0)) * (gamma + gamma.transpose());
  }
  return v;
}

ScoreTester::ScoreTester(RobustFitBlocks blocks_in, int hac_lag)
    : blocks_(std::move(blocks_in)), hac_lag_(std::max(hac_lag, 0)) {
  const RobustFitBlocks& blocks = blocks_;
  const size_t n = blocks.size();
  const Eigen::Index p = blocks.jacobian.cols();
  const Eigen::Index d = blocks.dimension();
  // As products of the stacked matrices (AccumulateCrossProducts): with row k of G = r_kᵀJ_k,
  // the gradients g_k = ρ'_k·J_kᵀr_k and the bread H = JᵀWJ + Gᵀdiag(2ρ''_k)G (W the row
  // weights ρ'_k); the meat is a long-run covariance.
  residual_jacobian_ = ResidualProducts(blocks, blocks.jacobian);
  gradients_ = blocks.rho1.asDiagonal() * residual_jacobian_;
  row_weights_ = blocks.rho1.replicate(1, d).transpose().reshaped();
  irls_nuisance_.noalias() =
      blocks.jacobian.transpose() * (row_weights_.asDiagonal() * blocks.jacobian);
  a_ = irls_nuisance_;
  a_.noalias() +=
      residual_jacobian_.transpose() * ((2.0 * blocks.rho2).asDiagonal() * residual_jacobian_);
  const Eigen::MatrixXd& a = a_;
  gradient_sum_ = gradients_.colwise().sum().transpose();
  gradient_outer_ = gradients_.transpose() * gradients_;
  a_nuisance_.compute(a);
  ok_ =
      n > 0 && a_nuisance_.info() == Eigen::Success && (a_nuisance_.vectorD().array() > 0.0).all();
  const double components = static_cast<double>(d) * n;
  small_sample_ = components > p ? components / (components - p) : 1.0;
}

ScoreTestResult ScoreTester::Test(const Eigen::MatrixXd& sensitivity) const {
  const size_t n = blocks_.size();
  const Eigen::Index p = blocks_.jacobian.cols();
  const Eigen::Index m = sensitivity.cols();
  ScoreTestResult result;
  result.dof = static_cast<int>(m);
  result.gamma = Eigen::VectorXd::Zero(m);
  result.gamma_covariance = Eigen::MatrixXd::Zero(m, m);
  result.absorption = Eigen::MatrixXd::Zero(p, m);
  result.absorbed = Eigen::VectorXd::Zero(p);
  result.contributions = Eigen::VectorXd::Zero(n);
  if (!ok_ || m == 0) return result;

  const CrossProducts c = AccumulateCrossProducts(blocks_, residual_jacobian_, row_weights_,
                                                  irls_nuisance_, sensitivity);
  const Eigen::MatrixXd w_eff = IrlsConcealment(c, &result);
  const Eigen::MatrixXd b = a_nuisance_.solve(c.a_tg);
  result.absorption = b;
  const Eigen::MatrixXd u = c.raw_scores - gradients_ * b;  // N × m projected score contributions.
  const Eigen::VectorXd score = u.colwise().sum().transpose();
  const Eigen::MatrixXd v = LongRunCovariance(u, hac_lag_) * small_sample_;
  // The efficient information from the loss's full second-order weight; where outliers make it
  // indefinite (ρ' + 2ρ''s < 0 beyond the Cauchy scale), its Gauss–Newton (IRLS) version.
  Eigen::LDLT<Eigen::MatrixXd> info_ldlt(c.a_gg - c.a_tg.transpose() * b);
  if (!PositiveDefinite(info_ldlt)) info_ldlt.compute(w_eff);
  const Eigen::LDLT<Eigen::MatrixXd> v_ldlt(v);
  if (!result.identifiable || !PositiveDefinite(v_ldlt) || !PositiveDefinite(info_ldlt)) {
    return result;
  }
  const Eigen::VectorXd v_inv_score = v_ldlt.solve(score);
  result.statistic = score.dot(v_inv_score);
  result.p_value = ChiSquareSurvival(result.statistic, result.dof);
  const Eigen::MatrixXd info_inv = info_ldlt.solve(Eigen::MatrixXd::Identity(m, m));
  result.gamma = -info_inv * score;
  result.gamma_covariance = info_inv * v * info_inv;
  result.absorbed = b * result.gamma;
  if (result.statistic > 0.0) {
    result.contributions = u * v_inv_score / std::sqrt(result.statistic);
  }
  return result;
}

namespace {

// xᵀM⁻¹x for a symmetric 2×2 M; false unless M is positive definite.
bool QuadraticOfInverse2(const Eigen::Matrix2d& m, const Eigen::Vector2d& x, double* value) {
  const double det = m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0);
  if (!(m(0, 0) > 0.0 && m(1, 1) > 0.0 && det > 0.0)) return false;
  *value =
      (m(1, 1) * x(0) * x(0) - (m(0, 1) + m(1, 0)) * x(0) * x(1) + m(0, 0) * x(1) * x(1)) / det;
  return true;
}

// The suffix sums of ScanChange's loop, in P × M fixed sizes where the caller knows them (the
// base fit's six parameters and a two-wheel change: three times faster) and dynamic ones
// otherwise. Fills scan->statistic, index and location; returns the best statistic (< 0: none).
template <int P, int M>
double ScanChangeSums(const RobustFitBlocks& blocks, const Eigen::MatrixXd& sensitivity,
                      const Eigen::MatrixXd& sr, const Eigen::MatrixXd& residual_jacobian,
                      const Eigen::MatrixXd& gradients, const Eigen::MatrixXd& a_nuisance,
                      const Eigen::VectorXd& gradient_sum, const Eigen::MatrixXd& gradient_outer,
                      double small_sample, size_t lo, size_t hi, ScoreTester::ChangeScan* scan) {
  using MatPP = Eigen::Matrix<double, P, P>;
  using MatPM = Eigen::Matrix<double, P, M>;
  using MatMM = Eigen::Matrix<double, M, M>;
  using MatMP = Eigen::Matrix<double, M, P>;
  using VecM = Eigen::Matrix<double, M, 1>;
  const size_t n = blocks.size();
  const Eigen::Index p = blocks.jacobian.cols(), m = sensitivity.cols(), d = blocks.dimension();
  const Eigen::LDLT<MatPP> nuisance{MatPP(a_nuisance)};
  // Fixed sizes: A⁻¹ once, then a product per split instead of a solve.
  MatPP nuisance_inverse;
  if constexpr (P != Eigen::Dynamic) nuisance_inverse = nuisance.solve(MatPP::Identity());
  const VecM zero_m = VecM::Zero(m);
  VecM sum_a = zero_m, a(m), score(m);
  MatPM sum_jmr = MatPM::Zero(p, m), b(p, m);
  MatMM sum_rmr = MatMM::Zero(m, m), sum_aa = MatMM::Zero(m, m), cross(m, m), v(m, m), info(m, m);
  MatMP sum_ag = MatMP::Zero(m, p);
  const MatPP outer(gradient_outer);
  const Eigen::Matrix<double, P, 1> g_sum(gradient_sum);
  Eigen::LDLT<MatMM> v_ldlt(m), info_ldlt(m);
  double best = -1.0, best_located = -1.0;
  for (size_t j = n; j-- > lo;) {
    const auto jacobian = blocks.jacobian.middleRows(d * j, d);
    const auto s = sensitivity.middleRows(d * j, d);
    const double w = blocks.rho1(j), w2 = 2.0 * blocks.rho2(j);
    const VecM srj = sr.row(j).transpose();
    a = w * srj;
    sum_a += a;
    sum_jmr.noalias() += w * (jacobian.transpose() * s);
    sum_jmr.noalias() += w2 * residual_jacobian.row(j).transpose() * srj.transpose();
    sum_rmr.noalias() += w * (s.transpose() * s);
    sum_rmr.noalias() += w2 * srj * srj.transpose();
    sum_aa.noalias() += a * a.transpose();
    sum_ag.noalias() += a * gradients.row(j);
    if (j > hi) continue;
    if constexpr (P == Eigen::Dynamic) {
      b = nuisance.solve(sum_jmr);
    } else {
      b.noalias() = nuisance_inverse * sum_jmr;
    }
    score = sum_a;
    score.noalias() -= b.transpose() * g_sum;
    cross.noalias() = sum_ag * b;
    v = sum_aa - cross - cross.transpose();
    v.noalias() += b.transpose() * outer * b;
    v *= small_sample;
    info = sum_rmr;
    info.noalias() -= sum_jmr.transpose() * b;
    if constexpr (M == 2) {
      // UᵀV⁻¹U and UᵀI⁻¹U by the 2×2 inverses (V, I positive definite: both diagonal entries
      // and the determinant positive).
      double statistic, located;
      if (!QuadraticOfInverse2(v, score, &statistic)) continue;
      if (!QuadraticOfInverse2(info, score, &located)) located = statistic;
      scan->statistic[j] = statistic;
      if (statistic > best) {
        best = statistic;
        scan->index = j;
      }
      if (located > best_located) {
        best_located = located;
        scan->location = j;
      }
      continue;
    }
    v_ldlt.compute(v);
    info_ldlt.compute(info);
    if (v_ldlt.info() != Eigen::Success || !(v_ldlt.vectorD().array() > 0.0).all()) continue;
    const double statistic = score.dot(v_ldlt.solve(score));
    scan->statistic[j] = statistic;
    if (statistic > best) {
      best = statistic;
      scan->index = j;
    }
    // The one-step likelihood ratio UᵀI_eff⁻¹U locates the change: unlike the empirical
    // variance, the information is not inflated by the change itself.
    const bool info_ok =
        info_ldlt.info() == Eigen::Success && (info_ldlt.vectorD().array() > 0.0).all();
    const double located = info_ok ? score.dot(info_ldlt.solve(score)) : statistic;
    if (located > best_located) {
      best_located = located;
      scan->location = j;
    }
  }
  return best;
}

}  // namespace

ScoreTester::ChangeScan ScoreTester::ScanChange(const Eigen::MatrixXd& sensitivity,
                                                double trim) const {
  ChangeScan scan;
  const size_t n = blocks_.size();
  const Eigen::Index p = blocks_.jacobian.cols();
  const Eigen::Index m = sensitivity.cols();
  const Eigen::Index d = blocks_.dimension();
  scan.statistic.assign(n, 0.0);
  if (!ok_ || n < 4 || m == 0) return scan;
  trim = std::clamp(trim, 0.0, 0.49);
  const size_t lo = std::max<size_t>(1, static_cast<size_t>(std::ceil(trim * n)));
  const size_t hi = std::min(n - 1, static_cast<size_t>(std::floor((1.0 - trim) * n)));

  // Suffix sums over k ≥ j, accumulated from the end (each sample's terms as in
  // AccumulateCrossProducts).
  const Eigen::MatrixXd sr = ResidualProducts(blocks_, sensitivity);
  const double best =
      p == 6 && m == 2
          ? ScanChangeSums<6, 2>(blocks_, sensitivity, sr, residual_jacobian_, gradients_, a_,
                                 gradient_sum_, gradient_outer_, small_sample_, lo, hi, &scan)
          : ScanChangeSums<Eigen::Dynamic, Eigen::Dynamic>(
                blocks_, sensitivity, sr, residual_jacobian_, gradients_, a_, gradient_sum_,
                gradient_outer_, small_sample_, lo, hi, &scan);
  if (best < 0.0) return scan;
  scan.sup_statistic = best;
  Eigen::MatrixXd masked = sensitivity;
  masked.topRows(d * scan.index).setZero();
  scan.at_best = Test(masked);
  // The HAC statistic at the best time replaces the short-range one in the sup.
  scan.sup_statistic = scan.at_best.statistic;
  scan.p_value = SupChiSquareSurvival(scan.sup_statistic, static_cast<int>(m), trim);
  return scan;
}

}  // namespace calib
