#ifndef CALIB_SOLVERS_COMMON_ARROW_TERMS_H_
#define CALIB_SOLVERS_COMMON_ARROW_TERMS_H_

#include <ceres/ceres.h>

#include <memory>
#include <vector>

// A least-squares problem's parameter blocks and residual blocks as plain lists, for the
// band-arrow solver (band_arrow_solver.h). A caller that owns its blocks and cost functions lists
// them here instead of building a ceres::Problem: at 10⁵ intervals with latent times, Ceres'
// maps of blocks and cost functions took a fifth of the timing-aware calibration to build and
// to tear down again, and the problem is rebuilt whenever the latent times change brackets.
namespace calib {

struct ArrowTerms {
  struct Block {
    double* values = nullptr;
    int size = 0;
    const ceres::Manifold* manifold = nullptr;  // Not owned.
    bool constant = false;
  };
  // Every block a residual uses; the non-latent ones become the globals in this order.
  std::vector<Block> blocks;
  // Per residual block: its cost function and loss (not owned; loss may be null) and its
  // parameter blocks, values[first_value[i], first_value[i + 1]).
  std::vector<const ceres::CostFunction*> costs;
  std::vector<const ceres::LossFunction*> losses;
  std::vector<int> first_value = {0};
  std::vector<double*> values;

  void AddBlock(double* block, int size, const ceres::Manifold* manifold = nullptr,
                bool constant = false) {
    blocks.push_back({block, size, manifold, constant});
  }
  void AddResidual(const ceres::CostFunction* cost, const ceres::LossFunction* loss,
                   const std::vector<double*>& blocks_of_residual) {
    costs.push_back(cost);
    losses.push_back(loss);
    values.insert(values.end(), blocks_of_residual.begin(), blocks_of_residual.end());
    first_value.push_back(static_cast<int>(values.size()));
  }
  size_t num_residuals() const { return costs.size(); }

  // The lists of a Ceres problem (its blocks and residuals in the problem's order).
  static ArrowTerms FromProblem(const ceres::Problem& problem);
  // A Ceres problem over the same blocks and residuals, owning none of the cost functions,
  // losses or manifolds (for Ceres' own solver as a reference).
  std::unique_ptr<ceres::Problem> ToProblem() const;
};

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_ARROW_TERMS_H_
