#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/common/suitesparse_alignment.h>
#include <gtest/gtest.h>
#include <suitesparse/SuiteSparse_config.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace calib {
namespace {

// The presets keep each refinement's own numbers (moving them would move the results).
TEST(SolverOptionsTest, PresetsKeepTheRefinementsTolerances) {
  const ceres::Solver::Options laser = MakeSolverOptions(LaserRefinementSettings(10000, 100, 2));
  EXPECT_EQ(laser.linear_solver_type, ceres::DENSE_NORMAL_CHOLESKY);
  EXPECT_EQ(laser.trust_region_strategy_type, ceres::LEVENBERG_MARQUARDT);
  EXPECT_EQ(laser.max_num_iterations, 100);
  EXPECT_EQ(laser.num_threads, 2);
  EXPECT_DOUBLE_EQ(laser.function_tolerance, 0.005 / 10000);
  EXPECT_EQ(MakeSolverOptions(LaserRefinementSettings(10, 100, 2)).function_tolerance, 1e-6);
  EXPECT_EQ(laser.gradient_tolerance, 1e-12);
  EXPECT_EQ(laser.parameter_tolerance, 1e-10);
  EXPECT_EQ(laser.initial_trust_region_radius,
            ceres::Solver::Options().initial_trust_region_radius);
  EXPECT_EQ(laser.logging_type, ceres::SILENT);

  const ceres::Solver::Options bearing = MakeSolverOptions(BearingAdjustmentSettings(200, 1, 1e10));
  EXPECT_EQ(bearing.linear_solver_type, ceres::SPARSE_NORMAL_CHOLESKY);
  EXPECT_EQ(bearing.max_num_iterations, 200);
  EXPECT_EQ(bearing.initial_trust_region_radius, 1e10);
  EXPECT_EQ(bearing.max_trust_region_radius, 1e16);
  EXPECT_EQ(bearing.function_tolerance, 1e-10);
  EXPECT_EQ(bearing.gradient_tolerance, 1e-14);
  EXPECT_EQ(bearing.parameter_tolerance, 1e-12);
}

TEST(SolverOptionsTest, CovarianceAppliesTheLoss) {
  const ceres::Covariance::Options options = MakeCovarianceOptions(3);
  EXPECT_EQ(options.num_threads, 3);
  EXPECT_EQ(options.algorithm_type, ceres::SPARSE_QR);
  EXPECT_TRUE(options.apply_loss_function);
}

TEST(SolverOptionsTest, ConvergenceIsReadFromTheTermination) {
  ceres::Solver::Summary summary;
  summary.termination_type = ceres::CONVERGENCE;
  EXPECT_TRUE(Converged(summary));
  summary.termination_type = ceres::NO_CONVERGENCE;
  EXPECT_FALSE(Converged(summary));
  EXPECT_NE(NotConvergedText("the fit", summary).find("the fit stopped after"), std::string::npos);
}

// Once options are made, SuiteSparse's blocks start on 64-byte boundaries (the alignment-dependent
// BLAS paths beneath then take the same path in every run); growing keeps the contents, and the
// blocks are still released by free(), as Ceres releases some of SPQR's.
TEST(SuiteSparseAlignmentTest, BlocksAreAlignedGrowWithTheirContentsAndFreeWithFree) {
  MakeCovarianceOptions(1);
  for (size_t bytes : {size_t{1}, size_t{24}, size_t{1000}, size_t{1} << 20}) {
    auto* block = static_cast<unsigned char*>(SuiteSparse_malloc(1, bytes));
    ASSERT_NE(block, nullptr);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(block) % 64, 0u) << bytes;
    std::memset(block, 0x5a, bytes);
    int ok = 0;
    block = static_cast<unsigned char*>(SuiteSparse_realloc(2 * bytes, bytes, 1, block, &ok));
    ASSERT_TRUE(ok);
    EXPECT_EQ(reinterpret_cast<uintptr_t>(block) % 64, 0u) << bytes;
    for (size_t i = 0; i < bytes; ++i) ASSERT_EQ(block[i], 0x5a) << bytes << " at " << i;
    std::free(block);
  }
  auto* zeros = static_cast<unsigned char*>(SuiteSparse_calloc(100, 8));
  ASSERT_NE(zeros, nullptr);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(zeros) % 64, 0u);
  for (int i = 0; i < 800; ++i) ASSERT_EQ(zeros[i], 0);
  SuiteSparse_free(zeros);
  AlignSuiteSparseAllocations();  // Again: nothing changes.
}

}  // namespace
}  // namespace calib
