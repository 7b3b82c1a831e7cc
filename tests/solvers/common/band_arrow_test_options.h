#ifndef CALIB_TESTS_SOLVERS_COMMON_BAND_ARROW_TEST_OPTIONS_H_
#define CALIB_TESTS_SOLVERS_COMMON_BAND_ARROW_TEST_OPTIONS_H_

#include <calib/solvers/common/band_arrow_solver.h>
#include <ceres/ceres.h>

// Tolerances tight enough that the band-arrow solve and Ceres' reference solve reach the same
// optimum to the digits the tests compare.
namespace calib::band_arrow_test {

inline BandArrowOptions TightBandArrowOptions() {
  BandArrowOptions options;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-12;
  options.parameter_tolerance = 1e-14;
  options.max_iterations = 200;
  return options;
}

inline ceres::Solver::Options TightCeresOptions() {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.function_tolerance = 1e-15;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-15;
  options.max_num_iterations = 500;
  return options;
}

}  // namespace calib::band_arrow_test

#endif  // CALIB_TESTS_SOLVERS_COMMON_BAND_ARROW_TEST_OPTIONS_H_
