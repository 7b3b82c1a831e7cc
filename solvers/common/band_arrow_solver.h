#ifndef CALIB_SOLVERS_COMMON_BAND_ARROW_SOLVER_H_
#define CALIB_SOLVERS_COMMON_BAND_ARROW_SOLVER_H_

#include <calib/core/status.h>
#include <calib/solvers/common/arrow_terms.h>
#include <ceres/ceres.h>

#include <memory>
#include <string>
#include <vector>

// Levenberg–Marquardt for a Ceres problem whose variables are a few dense "global" blocks and many
// latent blocks, each residual touching latents within a short window of an order given by the
// caller (sample times ordered by time, poses along their chain; a latent block may have a
// manifold). The normal equations are then an arrow: a banded latent block (w its half-bandwidth
// in tangent columns), a dense border and a small corner; one step costs a banded LDLᵀ and a
// Schur complement, O(n·w²), where Ceres' sparse Cholesky pays for the general pattern at every
// iteration. Its covariance: solvers/common/band_arrow_covariance.h.
//
// Robust losses are reweighted (ρ′JᵀJ, as Ceres does for ρ″ < 0). That overstates the curvature,
// so LM crawls along nearly the same step for many iterations; an accepted step whose gain beat
// its model by 20 % is repeated while the cost falls (a cost evaluation is a tenth of a Jacobian).
// Newton weights (ρ′I + 2ρ″rrᵀ, floored) were tried: their models overshoot on the latent times
// and they took as many iterations.
namespace calib {

struct BandArrowOptions {
  int max_iterations = 100;
  double function_tolerance = 1e-6;   // Relative cost decrease of an accepted step.
  double gradient_tolerance = 1e-10;  // max |∇cost| in tangent coordinates.
  double parameter_tolerance = 1e-10;
  // When positive, also converged once two accepted steps in a row move the globals by less than
  // this, in σ of their information with the latents marginalised (the Schur complement): the
  // globals have settled while the latents may still creep.
  double global_step_tolerance = 0.0;
  int num_threads = 1;
};

struct BandArrowSummary {
  int iterations = 0;
  bool converged = false;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int band_width = 0;  // Of the latent block (0: diagonal).
};

// Minimises the cost of `problem` over its non-constant parameter blocks. `latents` lists blocks
// in band order; every other non-constant block is a global (with its manifold, if any).
// Fails (and leaves the problem at the last accepted point) when the cost or the normal
// equations cannot be evaluated.
Status SolveBandArrow(const BandArrowOptions& options, const std::vector<double*>& latents,
                      const std::string& what, ceres::Problem* problem, BandArrowSummary* summary);

// The same, with the arrow's structure (blocks, residuals, band order) read from the problem once
// and kept for later solves: valid while no block or residual is added, removed or made
// constant. A solve reads the block values and the cost functions afresh.
class BandArrowSolver {
 public:
  BandArrowSolver();
  ~BandArrowSolver();
  BandArrowSolver(const BandArrowSolver&) = delete;
  BandArrowSolver& operator=(const BandArrowSolver&) = delete;

  Status Build(const std::vector<double*>& latents, ceres::Problem* problem);
  // The same from lists (arrow_terms.h): the blocks and cost functions must outlive the solver.
  Status Build(const std::vector<double*>& latents, const ArrowTerms& terms);
  Status Solve(const BandArrowOptions& options, const std::string& what,
               BandArrowSummary* summary) const;

 private:
  struct Structure;
  std::unique_ptr<Structure> structure_;
};

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_BAND_ARROW_SOLVER_H_
