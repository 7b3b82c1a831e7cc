#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/common/suitesparse_alignment.h>

#include <algorithm>
#include <cmath>

namespace calib {

ceres::Solver::Options MakeSolverOptions(const SolverSettings& settings) {
  AlignSuiteSparseAllocations();
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.linear_solver_type = settings.linear_solver;
  options.max_num_iterations = settings.max_iterations;
  options.num_threads = settings.num_threads;
  if (settings.initial_trust_region_radius) {
    options.initial_trust_region_radius = *settings.initial_trust_region_radius;
  }
  if (settings.max_trust_region_radius) {
    options.max_trust_region_radius = *settings.max_trust_region_radius;
  }
  options.function_tolerance = settings.function_tolerance;
  options.gradient_tolerance = settings.gradient_tolerance;
  options.parameter_tolerance = settings.parameter_tolerance;
  options.logging_type = ceres::SILENT;
  return options;
}

ceres::Covariance::Options MakeCovarianceOptions(int num_threads) {
  AlignSuiteSparseAllocations();
  ceres::Covariance::Options options;
  options.num_threads = num_threads;
  options.algorithm_type = ceres::SPARSE_QR;
  options.apply_loss_function = true;
  return options;
}

SolverSettings LaserRefinementSettings(size_t residual_blocks, int max_iterations,
                                       int num_threads) {
  SolverSettings s;
  s.linear_solver = ceres::DENSE_NORMAL_CHOLESKY;
  s.max_iterations = max_iterations;
  s.num_threads = num_threads;
  s.function_tolerance = std::min(1e-6, 0.005 / std::max<size_t>(1, residual_blocks));
  s.gradient_tolerance = 1e-12;
  s.parameter_tolerance = 1e-10;
  return s;
}

SolverSettings LaserEffectFitSettings(size_t residual_blocks, int max_iterations, int num_threads) {
  SolverSettings s;
  s.linear_solver = ceres::DENSE_NORMAL_CHOLESKY;
  s.max_iterations = max_iterations;
  s.num_threads = num_threads;
  s.function_tolerance = std::min(1e-8, 1e-3 / static_cast<double>(residual_blocks));
  s.gradient_tolerance = 1e-14;
  s.parameter_tolerance = 1e-12;
  return s;
}

SolverSettings BearingAdjustmentSettings(int max_iterations, int num_threads,
                                         double initial_trust_region_radius) {
  SolverSettings s;
  s.linear_solver = ceres::SPARSE_NORMAL_CHOLESKY;
  s.max_iterations = max_iterations;
  s.num_threads = num_threads;
  s.initial_trust_region_radius = initial_trust_region_radius;
  s.max_trust_region_radius = 1e16;
  s.function_tolerance = 1e-10;
  s.gradient_tolerance = 1e-14;
  s.parameter_tolerance = 1e-12;
  return s;
}

Status Solve(const SolverSettings& settings, const std::string& what, ceres::Problem* problem,
             ceres::Solver::Summary* summary) {
  ceres::Solver::Summary local_summary;
  ceres::Solve(MakeSolverOptions(settings), problem, &local_summary);
  if (summary != nullptr) *summary = local_summary;
  if (local_summary.termination_type == ceres::FAILURE ||
      !std::isfinite(local_summary.final_cost)) {
    return Status::NotConverged(what + " failed: " + local_summary.message);
  }
  return Status::Ok();
}

Status SolveInStages(const std::function<Status(ceres::Solver::Summary*)>& solve,
                     const std::function<void()>& redescend, ceres::Solver::Summary* summary,
                     const std::function<void(const ceres::Solver::Summary&)>& after_first) {
  ceres::Solver::Summary own;
  if (summary == nullptr) summary = &own;
  if (!redescend) return solve(summary);
  ceres::Solver::Summary first;
  CALIB_RETURN_IF_ERROR(solve(&first));
  if (after_first) after_first(first);
  redescend();
  CALIB_RETURN_IF_ERROR(solve(summary));
  summary->iterations.insert(summary->iterations.begin(), first.iterations.begin(),
                             first.iterations.end());
  return Status::Ok();
}

bool Converged(const ceres::Solver::Summary& summary) {
  return summary.termination_type == ceres::CONVERGENCE ||
         summary.termination_type == ceres::USER_SUCCESS;
}

std::string NotConvergedText(const std::string& what, const ceres::Solver::Summary& summary) {
  return what + " stopped after " + std::to_string(summary.iterations.size()) +
         " iterations without converging (" + summary.message + ")";
}

}  // namespace calib
