#ifndef CALIB_SOLVERS_COMMON_ROBUST_COVARIANCE_H_
#define CALIB_SOLVERS_COMMON_ROBUST_COVARIANCE_H_

#include <calib/core/status.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <Eigen/Dense>
#include <optional>

// The covariance of an M-estimator (a least-squares fit under a robust loss ρ), once for every
// refinement. Two forms:
//  - the scalar correction of the weighted Gauss–Newton covariance C = (Σ ρ'·JᵀJ)⁻¹ (what
//    ceres::Covariance returns with apply_loss_function for the Cauchy and Huber losses):
//      κ = mean(ρ')·mean(ρ'²·s/d) / mean(ρ' + 2ρ''·s/d)² · n/r
//    over the residual blocks (s = ‖r‖² whitened, d their dimension), with n residual components
//    and r their redundancy (n − p for p parameters, or Σ(1 − h) with leverages h). κ·C is the
//    sandwich below when the blocks are alike, and σ̂²(JᵀJ)⁻¹ for the plain squared loss;
//  - the sandwich H⁻¹·B·H⁻¹·n/r with H = Σ Jᵀ(ρ'·I + 2ρ''·r rᵀ)J and B = Σ ρ'²·Jᵀ r rᵀ J, which
//    stays honest when the residual scatter differs between kinds of motion.
namespace calib {

// A covariance and the loss correction κ it carries (1 for the sandwich, which needs none).
template <typename Matrix>
struct CorrectedCovariance {
  Matrix covariance;
  double kappa = 1.0;
};

// ρ'(s) and ρ''(s) of a loss (1 and 0 without one).
struct LossDerivatives {
  double rho1 = 1.0;
  double rho2 = 0.0;
};
LossDerivatives EvaluateLoss(const ceres::LossFunction* loss, double s);

// The three sums of κ, accumulated one residual block at a time.
struct LossCorrectionSums {
  double weight = 0.0;  // Σ ρ'.
  double meat = 0.0;    // Σ ρ'²·s/d.
  double bread = 0.0;   // Σ ρ' + 2ρ''·s/d.
  size_t blocks = 0;

  // One block of dimension d with squared whitened norm s.
  void Add(double s, const LossDerivatives& rho, int dimension = 1) {
    weight += rho.rho1;
    meat += rho.rho1 * rho.rho1 * s / dimension;
    bread += rho.rho1 + 2.0 * rho.rho2 * s / dimension;
    ++blocks;
  }
  void Add(double s, const ceres::LossFunction* loss, int dimension = 1) {
    Add(s, EvaluateLoss(loss, s), dimension);
  }
  // Another set of blocks' sums (a chunk of a parallel pass).
  void Add(const LossCorrectionSums& other) {
    weight += other.weight;
    meat += other.meat;
    bread += other.bread;
    blocks += other.blocks;
  }
};

// The scale of likelihood-ratio statistics mean(ρ'²s/d)/mean(ρ' + 2ρ''s/d) (2·Δcost/scale is χ²
// under the null; 1 for Gaussian residuals without a loss); empty when either sum is not positive.
std::optional<double> LikelihoodRatioScale(const LossCorrectionSums& sums);

// λ = mean(ρ' + 2ρ''s/d)/mean(ρ'), Newton over Gauss–Newton curvature; empty when either sum is not
// positive.
std::optional<double> CurvatureRatio(const LossCorrectionSums& sums);

// κ = mean(ρ')·mean(ρ'²s/d)/mean(ρ' + 2ρ''s/d)² · n/r (n residual components, r > 0 their
// redundancy). NotObservable when r ≤ 0 or the bread is not positive (no curvature left).
StatusOr<double> LossCorrection(const LossCorrectionSums& sums, double components,
                                double redundancy);

// H and B of the sandwich, accumulated one residual block at a time (P may be Eigen::Dynamic: then
// construct with the size).
template <int P>
struct SandwichSums {
  using Matrix = Eigen::Matrix<double, P, P>;
  using Vector = Eigen::Matrix<double, P, 1>;
  explicit SandwichSums(Eigen::Index size = P)
      : bread(Matrix::Zero(size, size)), meat(Matrix::Zero(size, size)) {}
  Matrix bread;  // H.
  Matrix meat;   // B.

  // A block with Jacobian j (d × P) and whitened residual r.
  template <typename JDerived, typename RDerived>
  void Add(const Eigen::MatrixBase<JDerived>& j, const Eigen::MatrixBase<RDerived>& r,
           const LossDerivatives& rho) {
    const Vector g = AddBread(j, r, rho);
    meat += rho.rho1 * rho.rho1 * g * g.transpose();
  }
  // H alone (for a meat computed otherwise, e.g. a long-run covariance); returns g = jᵀr.
  template <typename JDerived, typename RDerived>
  Vector AddBread(const Eigen::MatrixBase<JDerived>& j, const Eigen::MatrixBase<RDerived>& r,
                  const LossDerivatives& rho) {
    const Vector g = j.transpose() * r;
    bread += rho.rho1 * j.transpose() * j + 2.0 * rho.rho2 * g * g.transpose();
    return g;
  }
  SandwichSums& operator+=(const SandwichSums& other) {
    bread += other.bread;
    meat += other.meat;
    return *this;
  }
};

// H⁻¹·B·H⁻¹·n/r (κ = 1). NotObservable when H is singular or r ≤ 0.
template <typename Matrix>
StatusOr<CorrectedCovariance<Matrix>> SandwichCovariance(const Matrix& bread, const Matrix& meat,
                                                         double components, double redundancy) {
  if (!(redundancy > 0.0)) {
    return Status::NotObservable("too few residuals for a covariance");
  }
  const Eigen::LDLT<Matrix> ldlt(bread);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
    return Status::NotObservable("the information matrix is singular");
  }
  const Matrix inverse = ldlt.solve(Matrix::Identity(bread.rows(), bread.cols()));
  return CorrectedCovariance<Matrix>{inverse * meat * inverse * (components / redundancy), 1.0};
}
template <int P>
StatusOr<CorrectedCovariance<Eigen::Matrix<double, P, P>>> SandwichCovariance(
    const SandwichSums<P>& sums, double components, double redundancy) {
  return SandwichCovariance(sums.bread, sums.meat, components, redundancy);
}

// The smallest-looking covariance that holds two estimates of one: `model` (κ·H⁻¹, exact when
// the model is) and `sandwich` (honest when it is not): with model = L·Lᵀ and the eigenvalues λ_i
// of L⁻¹·sandwich·L⁻ᵀ (eigenvectors v_i), L·V·diag(max(λ_i, 1))·Vᵀ·Lᵀ. Every linear combination's
// variance is then at least the larger of its two. `largest_ratio`: max λ_i, how much more a
// combination varies than the model says. `model` when it is not positive definite.
struct DominatingCovarianceResult {
  Eigen::MatrixXd covariance;
  double largest_ratio = 1.0;
};
DominatingCovarianceResult DominatingCovariance(const Eigen::MatrixXd& model,
                                                const Eigen::MatrixXd& sandwich);

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_ROBUST_COVARIANCE_H_
