#ifndef CALIB_SOLVERS_COMMON_SOLVER_OPTIONS_H_
#define CALIB_SOLVERS_COMMON_SOLVER_OPTIONS_H_

#include <calib/core/status.h>
#include <ceres/ceres.h>

#include <cstddef>
#include <functional>
#include <optional>
#include <string>

// The one place that builds Ceres' solver and covariance options. Every refinement is
// Levenberg–Marquardt, silent; what differs between them is gathered in SolverSettings, and the
// settings of each refinement are the named presets below (side by side so that they compare).
namespace calib {

struct SolverSettings {
  ceres::LinearSolverType linear_solver = ceres::DENSE_NORMAL_CHOLESKY;
  int max_iterations = 100;
  int num_threads = 1;
  double function_tolerance = 1e-6;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  std::optional<double> initial_trust_region_radius;  // Ceres' default when empty.
  std::optional<double> max_trust_region_radius;
};

ceres::Solver::Options MakeSolverOptions(const SolverSettings& settings);

// Covariance of the robustified problem (the Jacobian carries the loss weights √ρ'), by sparse
// QR, which also handles the nuisance blocks (poses) of the bundle adjustment.
ceres::Covariance::Options MakeCovarianceOptions(int num_threads);

// The laser refinement over `residual_blocks` intervals: it stops once an iteration lowers the
// cost by less than ~0.01 (in units of whitened χ²/2): the step then moved the estimate by about a
// tenth of its sigma, and what remains is smaller still. The cost is about 1.5 per interval,
// hence the relative tolerance.
SolverSettings LaserRefinementSettings(size_t residual_blocks, int max_iterations, int num_threads);

// The laser refits with candidate effects: their costs are compared between models (likelihood
// ratios of a few units), so they stop when an iteration gains less than ~1e-3 in total.
SolverSettings LaserEffectFitSettings(size_t residual_blocks, int max_iterations, int num_threads);

// The bearing bundle adjustment. The stiff odometry chains make the normal equations badly
// conditioned: a small initial radius would damp the soft modes (the runs' shapes) for a dozen
// iterations, so it starts near Gauss–Newton (LM still backs off when a step fails). The cost is
// about half a unit per bearing; it stops once an iteration gains far less than a hundredth of a
// sigma's worth.
SolverSettings BearingAdjustmentSettings(int max_iterations, int num_threads,
                                         double initial_trust_region_radius);

// Runs the solver on `problem` (the summary into `summary` when not null); NotConverged, naming
// `what`, when Ceres fails or the cost is not finite. Stopping at the iteration limit is not a
// failure here: the caller reads Converged(summary) and reports it.
Status Solve(const SolverSettings& settings, const std::string& what, ceres::Problem* problem,
             ceres::Solver::Summary* summary);

// A robust problem's solves in two stages: `solve` under its first loss, then, when `redescend`
// is set, the switch to Tukey's biweight (not convex: it starts from that optimum) and `solve`
// again; `summary` (when not null) holds both stages' iterations. Without `redescend`, one solve.
// `after_first` (may be empty) is told the first stage's summary before the switch.
Status SolveInStages(
    const std::function<Status(ceres::Solver::Summary*)>& solve,
    const std::function<void()>& redescend, ceres::Solver::Summary* summary,
    const std::function<void(const ceres::Solver::Summary&)>& after_first = nullptr);

// Whether a solve ended by one of its convergence tests (not by its iteration or time limit).
bool Converged(const ceres::Solver::Summary& summary);

// "stopped after N iterations without converging (...)", for warnings.
std::string NotConvergedText(const std::string& what, const ceres::Solver::Summary& summary);

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_SOLVER_OPTIONS_H_
