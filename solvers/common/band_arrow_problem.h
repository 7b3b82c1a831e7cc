#ifndef CALIB_SOLVERS_COMMON_BAND_ARROW_PROBLEM_H_
#define CALIB_SOLVERS_COMMON_BAND_ARROW_PROBLEM_H_

#include <calib/core/status.h>
#include <calib/core/timing/banded_ldlt.h>
#include <ceres/ceres.h>

#include <Eigen/Core>
#include <vector>

// The internals of BandArrowSolver (band_arrow_solver.h): the arrow's structure, its evaluation
// into banded normal equations, and the damped step.
namespace calib {
namespace band_arrow_internal {

using RowMatrix = BandedLdlt::RowMajorMatrix;  // What the banded solves work on.

struct Block {
  double* values = nullptr;
  int size = 0;
  int tangent = 0;
  const ceres::Manifold* manifold = nullptr;
  int column = 0;  // Globals: first tangent column; latents: latent index.
  bool latent = false;
};

// A residual block; its per-block and per-column data sit in the problem's flat arrays.
struct Term {
  const ceres::CostFunction* cost = nullptr;
  const ceres::LossFunction* loss = nullptr;
  int first_block = 0, num_blocks = 0;  // Into term_values_, term_block_, term_offset_.
  int first_column = 0;                 // Into term_column_.
  int globals = 0, columns = 0;  // Tangent columns of its non-constant blocks, globals first.
  int first_latent = 0;          // Its lowest latent index (the number of latents if none).
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

// The arrow read from a Ceres problem: its blocks (latents in band order, then globals), its
// residuals in band order, and the pieces of one Levenberg–Marquardt iteration on them.
class BandArrowProblem {
 public:
  Status Build(const std::vector<double*>& latents, ceres::Problem* problem);
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

  int globals() const { return globals_; }
  int latents() const { return static_cast<int>(latent_blocks_.size()); }
  int width() const { return width_; }

 private:
  bool EvaluateRange(size_t begin, size_t end, ArrowSystem* system, double* cost) const;
  // Adds one residual's reweighted share ρ′JᵀJ, ρ′Jᵀr to the system; `jt` is scratch.
  void AccumulateTerm(const Term& term, int m, const double* r, double weight,
                      double* const* jacobians, const std::vector<RowMatrix>& plus, double* jt,
                      ArrowSystem* system) const;

  std::vector<Block> blocks_;
  std::vector<int> latent_blocks_;
  std::vector<Term> terms_;
  std::vector<double*> term_values_;  // Per term and block: the values,
  std::vector<int> term_block_;       // the index into blocks_ (−1: constant),
  std::vector<int> term_offset_;      // its first tangent column in the term's Jacobian;
  std::vector<int> term_column_;      // per term and tangent column: global column or latent.
  int globals_ = 0, width_ = 0;
  mutable std::vector<double> saved_;
  mutable std::vector<ArrowSystem> parts_;  // Per evaluation thread beyond the first.
};

}  // namespace band_arrow_internal
}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_BAND_ARROW_PROBLEM_H_
