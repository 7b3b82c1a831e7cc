#ifndef CALIB_SOLVERS_COMMON_FUSED_NORMAL_COST_H_
#define CALIB_SOLVERS_COMMON_FUSED_NORMAL_COST_H_

#include <calib/solvers/common/parallel_chunks.h>
#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <type_traits>
#include <vector>

namespace calib {

// Many robustified residual blocks r_k (D values each) over the same N parameters, presented to
// Ceres as one block of N + 1 values: a million intervals then cost Ceres one block, not a million
// blocks and a 3N×6 Jacobian, and each evaluation is one pass (in parallel chunks) over them.
//
// Per item, Ceres' own corrector (Triggs et al.; ceres/internal/corrector.cc) turns (r_k, J_k) and
// ρ(s_k), s_k = ‖r_k‖², into r̃_k = c_k·r_k and J̃_k = √ρ'_k·(J_k − a_k·r_k·r_kᵀJ_k) (for ρ'' ≤ 0,
// as for every loss here, c_k = √ρ'_k and a_k = 0). The sums H = Σ J̃ᵀJ̃, g = Σ J̃ᵀr̃ and Σρ(s_k)
// are then written as R = Λ^½Vᵀ (H = VΛVᵀ), r = Λ^-½Vᵀg and a last value e with no derivative,
// e² = Σρ − gᵀH⁺g (≥ 0: ρ concave, so ρ(s) ≥ ρ'(s)·s, and gᵀH⁺g ≤ Σ‖r̃_k‖² is a projection). Then
// RᵀR = H, Rᵀr = g and ½(‖r‖² + e²) = ½Σρ: Ceres' cost, gradient, Gauss–Newton matrix, Jacobi
// scaling and model decrease equal those of the separate blocks, and so do its LM steps and
// ceres::Covariance (to rounding). A cost-only evaluation (no Jacobian asked) writes (0, √Σρ)
// after a pass without derivatives.
//
// The linearization is item k's whitened residual at the parameters (blocks as Ceres passes them)
// and, when `jacobian` is not null, its derivative along the concatenated blocks; false: not
// evaluable. Its type is a template parameter so that a lambda inlines into the pass (a
// std::function call per item cost a tenth of a pass); NewFusedNormalCost deduces it. It may
// instead take the parameters alone and return the per-item function (k, r, jacobian) → bool,
// so that what all items share (a sine of a parameter) is computed once per pass.
template <int D, int N>
using FusedLinearize =
    std::function<bool(size_t k, const double* const* parameters, Eigen::Matrix<double, D, 1>* r,
                       Eigen::Matrix<double, D, N>* jacobian)>;

template <int D, int N, typename F = FusedLinearize<D, N>>
class FusedNormalCost : public ceres::CostFunction {
 public:
  using Residual = Eigen::Matrix<double, D, 1>;
  using Jacobian = Eigen::Matrix<double, D, N>;
  using Linearize = F;

  // Chunks of at least this many items (a closed-form linearization: tens of µs, against a
  // helper's wake-up of about 20 µs); heavier ones (automatic derivatives) pay with smaller chunks.
  static constexpr size_t kDefaultMinChunk = 500;

  // `loss` (null: plain least squares) is read at each evaluation, so a ceres::LossFunctionWrapper
  // swapped after construction applies; it must outlive the cost.
  FusedNormalCost(std::vector<int> block_sizes, size_t num_items, Linearize linearize,
                  const ceres::LossFunction* loss, int num_threads,
                  size_t min_chunk = kDefaultMinChunk)
      : num_items_(num_items),
        linearize_(std::move(linearize)),
        loss_(loss),
        num_threads_(num_threads),
        min_chunk_(min_chunk) {
    set_num_residuals(N + 1);
    *mutable_parameter_block_sizes() = std::move(block_sizes);
  }

  // Speculation: a cost-only evaluation also forms the normal equations and keeps them for a
  // Jacobian evaluation at the same parameters right after it, which Ceres' trust region asks for
  // whenever it takes the step whose cost it has just evaluated (one pass instead of two: on a
  // million intervals the refinement's cost-only passes were 3 of 7). For linearizations whose
  // residuals with and without the Jacobian agree (bit for bit, or the cost changes by rounding),
  // whose Jacobian costs about what the residuals do, and which are evaluated from one thread at
  // a time (as Ceres does a block). The owner calls ForgetSpeculation() whenever something other
  // than the parameters changes the items (their whitening, the loss).
  void set_speculate(bool speculate) { speculate_ = speculate; }
  void ForgetSpeculation() const { speculated_.valid = false; }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    bool want_jacobian = false;
    for (size_t b = 0; jacobians != nullptr && b < parameter_block_sizes().size(); ++b) {
      want_jacobian = want_jacobian || jacobians[b] != nullptr;
    }
    const bool kept = want_jacobian && speculated_.valid && SameParameters(parameters);
    const Sums sums = kept ? speculated_.sums : Accumulate(parameters, want_jacobian || speculate_);
    speculated_.valid = false;
    if (!want_jacobian && speculate_) Keep(parameters, sums);
    if (!sums.ok || !std::isfinite(sums.rho)) return false;
    Eigen::Map<Eigen::Matrix<double, N + 1, 1>> out(residuals);
    out.setZero();
    if (!want_jacobian) {
      out(N) = std::sqrt(std::max(0.0, sums.rho));
      return true;
    }
    if (!sums.hessian.allFinite() || !sums.gradient.allFinite()) return false;
    const Eigen::Matrix<double, N, N> hessian =
        sums.hessian.template selfadjointView<Eigen::Upper>();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(hessian);
    const Eigen::Matrix<double, N, 1> lambda = eigen.eigenvalues();
    // Directions the data do not reach get no row (as a rank-deficient Jacobian would give none).
    const double floor = std::max(lambda.maxCoeff(), 0.0) * 1e-30;
    Eigen::Matrix<double, N + 1, N> root = Eigen::Matrix<double, N + 1, N>::Zero();
    const Eigen::Matrix<double, N, 1> projected = eigen.eigenvectors().transpose() * sums.gradient;
    for (int i = 0; i < N; ++i) {
      if (!(lambda(i) > floor)) continue;
      const double sqrt_lambda = std::sqrt(lambda(i));
      root.row(i) = sqrt_lambda * eigen.eigenvectors().col(i).transpose();
      out(i) = projected(i) / sqrt_lambda;
    }
    out(N) = std::sqrt(std::max(0.0, sums.rho - out.template head<N>().squaredNorm()));
    int column = 0;
    for (size_t b = 0; b < parameter_block_sizes().size(); ++b) {
      const int size = parameter_block_sizes()[b];
      if (jacobians[b] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, N + 1, Eigen::Dynamic, Eigen::RowMajor>>(
            jacobians[b], N + 1, size) = root.middleCols(column, size);
      }
      column += size;
    }
    return true;
  }

 private:
  struct Sums {
    Eigen::Matrix<double, N, N> hessian = Eigen::Matrix<double, N, N>::Zero();
    Eigen::Matrix<double, N, 1> gradient = Eigen::Matrix<double, N, 1>::Zero();
    double rho = 0.0;
    bool ok = true;
  };

  Sums Accumulate(const double* const* parameters, bool want_jacobian) const {
    if constexpr (std::is_invocable_v<const F&, const double* const*>) {
      return AccumulateItems(linearize_(parameters), want_jacobian);
    } else {
      return AccumulateItems(
          [&](size_t k, Residual* r, Jacobian* j) { return linearize_(k, parameters, r, j); },
          want_jacobian);
    }
  }

  bool SameParameters(double const* const* parameters) const {
    size_t at = 0;
    for (size_t b = 0; b < parameter_block_sizes().size(); ++b) {
      const size_t bytes = sizeof(double) * parameter_block_sizes()[b];
      if (std::memcmp(parameters[b], speculated_.parameters.data() + at, bytes) != 0) return false;
      at += parameter_block_sizes()[b];
    }
    return true;
  }
  void Keep(double const* const* parameters, const Sums& sums) const {
    speculated_.parameters.clear();
    for (size_t b = 0; b < parameter_block_sizes().size(); ++b) {
      speculated_.parameters.insert(speculated_.parameters.end(), parameters[b],
                                    parameters[b] + parameter_block_sizes()[b]);
    }
    speculated_.sums = sums;
    speculated_.valid = true;
  }

  template <typename Item>
  Sums AccumulateItems(const Item& item, bool want_jacobian) const {
    std::vector<Sums> partial(SplitCount(num_items_, min_chunk_));
    ParallelSplit(num_items_, num_threads_, min_chunk_, [&](size_t c, size_t begin, size_t end) {
      // Summed on the thread's own stack and stored once: partial sums side by side in one
      // vector share cache lines, and writing them per item made two threads slower than one.
      Sums sums;
      AccumulateRange(item, want_jacobian, begin, end, &sums);
      partial[c] = sums;
    });
    for (size_t c = 1; c < partial.size(); ++c) {
      partial[0].hessian += partial[c].hessian;
      partial[0].gradient += partial[c].gradient;
      partial[0].rho += partial[c].rho;
      partial[0].ok = partial[0].ok && partial[c].ok;
    }
    Eigen::Matrix<double, N, N>& hessian = partial[0].hessian;
    hessian.template triangularView<Eigen::StrictlyLower>() = hessian.transpose();
    return partial[0];
  }

  template <typename Item>
  void AccumulateRange(const Item& item, bool want_jacobian, size_t begin, size_t end,
                       Sums* out) const {
    Sums& sums = *out;
    Residual r;
    Jacobian j;
    for (size_t k = begin; k < end; ++k) {
      sums.ok = item(k, &r, want_jacobian ? &j : nullptr);
      if (!sums.ok) return;
      const double s = r.squaredNorm();
      double rho[3] = {s, 1.0, 0.0};
      if (loss_ != nullptr) loss_->Evaluate(s, rho);
      sums.rho += rho[0];
      if (!want_jacobian || !(rho[1] > 0.0)) continue;
      const double sqrt_rho1 = std::sqrt(rho[1]);
      double scaling = sqrt_rho1;
      if (s > 0.0 && rho[2] > 0.0) {
        // Ceres' curvature correction: α the smaller root of ½α² − α − (ρ''/ρ')·s = 0.
        const double alpha = 1.0 - std::sqrt(1.0 + 2.0 * s * rho[2] / rho[1]);
        scaling = sqrt_rho1 / (1.0 - alpha);
        j -= (alpha / s) * r * (r.transpose() * j);
      }
      const Jacobian corrected = sqrt_rho1 * j;
      // The upper triangle only, in loops the compiler unrolls (Eigen's rank update goes through
      // its general kernel, several times slower at these sizes); the lower is mirrored once.
      for (int b = 0; b < N; ++b) {
        for (int a = 0; a <= b; ++a) sums.hessian(a, b) += corrected.col(a).dot(corrected.col(b));
      }
      sums.gradient.noalias() += corrected.transpose() * (scaling * r);
    }
  }

  struct Speculation {
    bool valid = false;
    std::vector<double> parameters;  // The blocks' values, concatenated.
    Sums sums;
  };

  size_t num_items_;
  Linearize linearize_;
  bool speculate_ = false;
  mutable Speculation speculated_;
  const ceres::LossFunction* loss_;
  int num_threads_;
  size_t min_chunk_;
};

// new FusedNormalCost<D, N, F> with F deduced from `linearize` (a lambda).
template <int D, int N, typename F>
FusedNormalCost<D, N, F>* NewFusedNormalCost(
    std::vector<int> block_sizes, size_t num_items, F linearize, const ceres::LossFunction* loss,
    int num_threads, size_t min_chunk = FusedNormalCost<D, N, F>::kDefaultMinChunk) {
  return new FusedNormalCost<D, N, F>(std::move(block_sizes), num_items, std::move(linearize), loss,
                                      num_threads, min_chunk);
}

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_FUSED_NORMAL_COST_H_
