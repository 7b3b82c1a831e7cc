#ifndef CALIB_SOLVERS_COMMON_BAND_ARROW_PROBLEM_H_
#define CALIB_SOLVERS_COMMON_BAND_ARROW_PROBLEM_H_

#include <calib/core/status.h>
#include <calib/core/timing/banded_ldlt.h>
#include <calib/solvers/common/arrow_terms.h>
#include <ceres/ceres.h>

#include <Eigen/Core>
#include <unordered_map>
#include <vector>

// The internals of BandArrowSolver (band_arrow_solver.h): the arrow's structure, its evaluation
// into banded normal equations, and the damped step.
namespace calib {
namespace band_arrow_internal {

using RowMatrix = BandedLdlt::RowMajorMatrix;  // What the banded solves work on.

// The largest residual block it takes (the timing-aware interval: 3 residuals, at most 16
// parameters in at most 10 blocks; a bearing odometry term: 3 residuals, 11 parameters).
constexpr int kMaxResiduals = 4, kMaxColumns = 24, kMaxBlocks = 12;
// Residuals per evaluation thread, at least.
constexpr size_t kMinChunk = 256;

struct Block {
  double* values = nullptr;
  int size = 0;
  int tangent = 0;
  const ceres::Manifold* manifold = nullptr;
  int column = 0;  // First tangent column among the globals, resp. the latents.
  bool latent = false;
};

// A residual block; its per-block and per-column data sit in the problem's flat arrays.
struct Term {
  int index = 0;  // In the problem's order of residual blocks.
  const ceres::CostFunction* cost = nullptr;
  const ceres::LossFunction* loss = nullptr;
  int first_block = 0, num_blocks = 0;  // Into term_values_, term_block_, term_offset_.
  int first_column = 0;                 // Into term_column_.
  int globals = 0, columns = 0;  // Tangent columns of its non-constant blocks, globals first.
  int first_latent = 0;          // Its lowest latent column (the number of them if none).
};

// The normal equations H = JᵀWJ, g = Jᵀρ′r, split as globals (g) and latents (l, banded).
struct ArrowSystem {
  Eigen::MatrixXd h_gg, band;
  RowMatrix h_lg;  // Row-major: a residual adds to a few latents' rows.
  Eigen::VectorXd g_g, g_l;
  double cost = 0.0;
  void Reset(int globals, int latents, int width) {
    h_gg = Eigen::MatrixXd::Zero(globals, globals);
    h_lg = RowMatrix::Zero(latents, globals);
    band = Eigen::MatrixXd::Zero(width + 1, latents);
    g_g = Eigen::VectorXd::Zero(globals);
    g_l = Eigen::VectorXd::Zero(latents);
    cost = 0.0;
  }
  void Add(const ArrowSystem& o) {
    h_gg += o.h_gg, h_lg += o.h_lg, band += o.band, g_g += o.g_g, g_l += o.g_l, cost += o.cost;
  }
};

// The arrow read from a Ceres problem or from lists of its terms: its blocks (latents in band
// order, then globals), its residuals in band order, and the pieces of one Levenberg–Marquardt
// iteration on them.
class BandArrowProblem {
 public:
  Status Build(const std::vector<double*>& latents, ceres::Problem* problem);
  Status Build(const std::vector<double*>& latents, const ArrowTerms& terms);
  // Cost (½Σρ) at the current values, with the normal equations when `system` is not null.
  bool Evaluate(ArrowSystem* system, int num_threads, double* cost) const;
  // Δ from (H + λD)Δ = −g; false when the damped system is not positive definite.
  // `global_step` is √(Δ_gᵀ S Δ_g), S the Schur complement of the latents.
  bool Step(const ArrowSystem& system, double lambda, Eigen::VectorXd* delta_g,
            Eigen::VectorXd* delta_l, double* model_decrease, double* global_step) const;
  void Save() const;
  void Restore() const;
  void Apply(const Eigen::VectorXd& delta_g, const Eigen::VectorXd& delta_l) const;
  double ParameterNorm() const;
  // At the current values, with the weights of the steps (ρ′JᵀJ, which is what ceres::Covariance
  // uses for a loss with ρ″ ≤ 0): the covariance of `blocks` in their ambient coordinates (zero
  // for constant blocks; `sizes` their ambient sizes), and, when `leverages` is not null,
  // ρ′·tr(J·Σ·Jᵀ) of every residual block in the problem's order. Fails with kNotObservable when
  // the information is singular.
  Status Covariance(const std::vector<const double*>& blocks, const std::vector<int>& sizes,
                    int num_threads, Eigen::MatrixXd* covariance,
                    std::vector<double>* leverages) const;

  int globals() const { return globals_; }
  int latents() const { return latent_columns_; }  // Tangent columns of the latent blocks.
  int width() const { return width_; }

 private:
  bool EvaluateRange(size_t begin, size_t end, ArrowSystem* system, double* cost) const;
  // The manifolds' Plus Jacobians at the current values, per block (empty without a manifold).
  std::vector<RowMatrix> PlusJacobians() const;
  // A residual's tangent Jacobian, column-major m × term.columns (globals first), into `jt`.
  void TangentJacobian(const Term& term, int m, double* const* jacobians,
                       const std::vector<RowMatrix>& plus, double* jt) const;
  // Adds one residual's reweighted share ρ′JᵀJ, ρ′Jᵀr to the system; `jt` is scratch.
  void AccumulateTerm(const Term& term, int m, const double* r, double weight,
                      double* const* jacobians, const std::vector<RowMatrix>& plus, double* jt,
                      ArrowSystem* system) const;
  // ρ′·tr(J·Σ·Jᵀ) of terms_[begin, end) into (*leverages)[term.index]; `sigma(a, b)` gives Σ
  // between two of a term's columns (its column indices, globals first).
  template <typename Sigma>
  bool TermLeverages(size_t begin, size_t end, const std::vector<RowMatrix>& plus,
                     const Sigma& sigma, std::vector<double>* leverages) const;

  std::vector<Block> blocks_;
  std::unordered_map<const double*, int> block_index_;  // Non-constant blocks by their values.
  std::vector<int> latent_blocks_;
  std::vector<Term> terms_;
  std::vector<double*> term_values_;  // Per term and block: the values,
  std::vector<int> term_block_;       // the index into blocks_ (−1: constant),
  std::vector<int> term_offset_;      // its first tangent column in the term's Jacobian;
  std::vector<int> term_column_;      // per term and tangent column: global column or latent.
  int globals_ = 0, latent_columns_ = 0, width_ = 0;
  mutable std::vector<double> saved_;
  mutable std::vector<ArrowSystem> parts_;  // Per evaluation thread beyond the first.
};

}  // namespace band_arrow_internal
}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_BAND_ARROW_PROBLEM_H_
