#ifndef CALIB_SOLVERS_DIAGNOSIS_RESIDUAL_STRUCTURE_H_
#define CALIB_SOLVERS_DIAGNOSIS_RESIDUAL_STRUCTURE_H_

#include <calib/solvers/stats/change_point.h>

#include <Eigen/Core>
#include <string>
#include <vector>

// Structure left in the residuals of a fit, whether or not a candidate explains it: the binned
// means of the residuals against each covariate and a change of their mean over time, Holm
// over these tests at the family-wise level.
namespace calib {

// Per sample (an interval, a bearing) of one fit.
struct ResidualSeries {
  std::vector<std::string> covariate_names;
  std::vector<std::vector<double>> covariates;  // Per covariate, per sample.
  // Per covariate, CovariateOrder of it where the caller has it already; empty: sorted here.
  std::vector<std::vector<size_t>> covariate_orders;
  Eigen::MatrixXd values;   // N × d: what the binned means test.
  Eigen::VectorXd weights;  // N: the loss's weights ρ'.
  // N × d, unit variance per sample: what the change test (CUSUM) scans. Empty: no change test.
  Eigen::MatrixXd change_series;
  std::vector<double> split_time_s;  // Per sample: the time a change before it is reported at.
};

struct StructureOptions {
  int bins = 10;
  double change_trim = 0.05;
  double alpha = 0.01;
};

// The problem's words. Nothing found: `none` + "(smallest p, family-wise level α)."; else
// `found` + [covariate_prefix + covariate_words[c] + " (binned means, p)"] + [" and "] +
// [change_format(time) + " (p)"] + ": a mismatch that the adopted model does not explain."
struct StructureWords {
  std::vector<std::string> covariate_words;  // In the order of covariate_names.
  std::string none;
  std::string found;
  std::string covariate_prefix;  // Before the covariate's words ("follow ").
  std::string change_format;     // printf format of the change time (s).
};

ResidualStructure TestResidualStructure(const ResidualSeries& series,
                                        const StructureOptions& options,
                                        const StructureWords& words);

}  // namespace calib

#endif  // CALIB_SOLVERS_DIAGNOSIS_RESIDUAL_STRUCTURE_H_
