#ifndef CALIB_SOLVERS_DIAGNOSIS_MULTIPLE_TESTING_H_
#define CALIB_SOLVERS_DIAGNOSIS_MULTIPLE_TESTING_H_

#include <cstddef>
#include <vector>

// Holm's step-down procedure: controls the family-wise error rate at α over m tests.
namespace calib {

struct HolmStep {
  size_t index = 0;  // Into the p-values given.
  double p_value = 1.0;
  double level = 0.0;     // α/(m − rank).
  bool rejected = false;  // p ≤ level here and at every smaller p-value.
};

// The tests in ascending order of p-value (ties keep their given order), each compared with
// α/(m − rank); the first one not rejected stops the procedure.
std::vector<HolmStep> Holm(const std::vector<double>& p_values, double alpha);

}  // namespace calib

#endif  // CALIB_SOLVERS_DIAGNOSIS_MULTIPLE_TESTING_H_
