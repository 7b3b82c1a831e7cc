#include <calib/solvers/common/arrow_terms.h>

namespace calib {

ArrowTerms ArrowTerms::FromProblem(const ceres::Problem& problem) {
  ArrowTerms terms;
  std::vector<double*> all;
  problem.GetParameterBlocks(&all);
  for (double* block : all) {
    terms.AddBlock(block, problem.ParameterBlockSize(block), problem.GetManifold(block),
                   problem.IsParameterBlockConstant(block));
  }
  std::vector<ceres::ResidualBlockId> ids;
  problem.GetResidualBlocks(&ids);
  std::vector<double*> values;
  for (const ceres::ResidualBlockId id : ids) {
    problem.GetParameterBlocksForResidualBlock(id, &values);
    terms.AddResidual(problem.GetCostFunctionForResidualBlock(id),
                      problem.GetLossFunctionForResidualBlock(id), values);
  }
  return terms;
}

std::unique_ptr<ceres::Problem> ArrowTerms::ToProblem() const {
  ceres::Problem::Options options;
  options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  auto problem = std::make_unique<ceres::Problem>(options);
  for (const Block& b : blocks) {
    problem->AddParameterBlock(b.values, b.size, const_cast<ceres::Manifold*>(b.manifold));
    if (b.constant) problem->SetParameterBlockConstant(b.values);
  }
  for (size_t i = 0; i < costs.size(); ++i) {
    std::vector<double*> residual_blocks(values.begin() + first_value[i],
                                         values.begin() + first_value[i + 1]);
    problem->AddResidualBlock(const_cast<ceres::CostFunction*>(costs[i]),
                              const_cast<ceres::LossFunction*>(losses[i]), residual_blocks);
  }
  return problem;
}

}  // namespace calib
