#include <calib/solvers/common/band_arrow_problem.h>
#include <calib/solvers/common/band_arrow_solver.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace calib {
namespace {

using band_arrow_internal::ArrowSystem;
using band_arrow_internal::BandArrowProblem;

// Reweighting overstates the curvature of a robust loss (its model gains less than the step
// does): after such a step, up to this many more of the same while the cost keeps falling.
constexpr int kExtensions = 3;

Status SolveArrow(const BandArrowOptions& options, const std::string& what,
                  const BandArrowProblem& arrow, BandArrowSummary* summary) {
  BandArrowSummary out;
  out.band_width = arrow.width();
  ArrowSystem system;
  double cost = 0.0;
  if (!arrow.Evaluate(&system, options.num_threads, &cost) || !std::isfinite(cost)) {
    return Status::NotConverged(what + " failed: the cost is not finite at the starting point");
  }
  out.initial_cost = cost;
  double lambda = 1e-4, nu = 2.0;
  bool fresh = true;        // `system` is at the current point.
  int settled_globals = 0;  // Accepted steps in a row below options.global_step_tolerance.
  for (; out.iterations < options.max_iterations && !out.converged; ++out.iterations) {
    if (!fresh && !arrow.Evaluate(&system, options.num_threads, &cost)) {
      return Status::NotConverged(what + " failed: the Jacobian could not be evaluated");
    }
    fresh = true;
    if (std::max(system.g_g.lpNorm<Eigen::Infinity>(), system.g_l.lpNorm<Eigen::Infinity>()) <=
        options.gradient_tolerance) {
      out.converged = true;
      break;
    }
    Eigen::VectorXd delta_g, delta_l;
    double model_decrease = 0.0, global_step = 0.0;
    if (!arrow.Step(system, lambda, &delta_g, &delta_l, &model_decrease, &global_step) ||
        !(model_decrease > 0.0)) {
      lambda *= nu, nu *= 2.0;
      continue;
    }
    const double step_norm = std::sqrt(delta_g.squaredNorm() + delta_l.squaredNorm());
    if (step_norm <=
        options.parameter_tolerance * (arrow.ParameterNorm() + options.parameter_tolerance)) {
      out.converged = true;
      break;
    }
    arrow.Save();
    arrow.Apply(delta_g, delta_l);
    double trial = 0.0;
    const bool ok = arrow.Evaluate(nullptr, options.num_threads, &trial) && std::isfinite(trial);
    const double ratio = ok ? (cost - trial) / model_decrease : -1.0;
    if (ratio > 1e-3) {
      // The model underestimated the gain (reweighting overstates the curvature of a robust loss):
      // go on along the same step while the cost keeps falling.
      for (int e = 0; e < kExtensions && ratio > 1.2; ++e) {
        arrow.Apply(delta_g, delta_l);
        double further = 0.0;
        if (!(arrow.Evaluate(nullptr, options.num_threads, &further) && further < trial)) {
          arrow.Apply(-delta_g, -delta_l);
          break;
        }
        trial = further;
      }
      const double decrease = cost - trial;
      cost = trial;
      fresh = false;
      lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3));
      nu = 2.0;
      settled_globals = global_step < options.global_step_tolerance ? settled_globals + 1 : 0;
      out.converged = decrease <= options.function_tolerance * cost || settled_globals >= 2;
    } else {
      arrow.Restore();
      lambda *= nu, nu *= 2.0;
    }
    if (lambda > 1e32) break;
  }
  out.final_cost = cost;
  if (summary) *summary = out;
  return Status::Ok();
}

}  // namespace

struct BandArrowSolver::Structure {
  BandArrowProblem arrow;
};

BandArrowSolver::BandArrowSolver() = default;
BandArrowSolver::~BandArrowSolver() = default;

Status BandArrowSolver::Build(const std::vector<double*>& latents, ceres::Problem* problem) {
  structure_ = std::make_unique<Structure>();
  const Status built = structure_->arrow.Build(latents, problem);
  if (!built.ok()) structure_.reset();
  return built;
}

Status BandArrowSolver::Build(const std::vector<double*>& latents, const ArrowTerms& terms) {
  structure_ = std::make_unique<Structure>();
  const Status built = structure_->arrow.Build(latents, terms);
  if (!built.ok()) structure_.reset();
  return built;
}

Status BandArrowSolver::Solve(const BandArrowOptions& options, const std::string& what,
                              BandArrowSummary* summary) const {
  if (!structure_) return Status::Internal(what + ": the band-arrow solver was not built");
  return SolveArrow(options, what, structure_->arrow, summary);
}

Status SolveBandArrow(const BandArrowOptions& options, const std::vector<double*>& latents,
                      const std::string& what, ceres::Problem* problem, BandArrowSummary* summary) {
  BandArrowSolver solver;
  CALIB_RETURN_IF_ERROR(solver.Build(latents, problem));
  return solver.Solve(options, what, summary);
}

}  // namespace calib
