#include <calib/core/text_format.h>
#include <calib/solvers/diagnosis/multiple_testing.h>
#include <calib/solvers/diagnosis/residual_structure.h>

namespace calib {
namespace {

std::string Statement(const ResidualStructure& s, size_t covariate, double smallest_p, double alpha,
                      const StructureWords& words) {
  if (!s.found) {
    return words.none + "(smallest " + PValueText(smallest_p) + ", family-wise level " +
           Format("%.2g", alpha) + ").";
  }
  std::string text = words.found;
  if (!s.covariate.empty()) {
    text += words.covariate_prefix + words.covariate_words[covariate] + " (binned means, " +
            PValueText(s.p_value) + ")";
  }
  if (s.change_time_s >= 0.0) {
    if (!s.covariate.empty()) text += " and ";
    text += Format(words.change_format.c_str(), s.change_time_s) + " (" +
            PValueText(s.change_p_value) + ")";
  }
  return text + ": a mismatch that the adopted model does not explain.";
}

}  // namespace

ResidualStructure TestResidualStructure(const ResidualSeries& series,
                                        const StructureOptions& options,
                                        const StructureWords& words) {
  ResidualStructure structure;
  std::vector<double> p_values;  // The covariates', then the change test's.
  for (size_t c = 0; c < series.covariates.size(); ++c) {
    const std::vector<double>& covariate = series.covariates[c];
    p_values.push_back(
        (c < series.covariate_orders.size()
             ? BinByCovariate(covariate, series.covariate_orders[c], series.values, series.weights,
                              options.bins)
             : BinByCovariate(covariate, series.values, series.weights, options.bins))
            .p_value);
  }
  size_t split = 0;
  if (series.change_series.size() > 0) {
    structure.change_p_value =
        ConstantMeanPValue(series.change_series, options.change_trim, &split);
  }
  p_values.push_back(structure.change_p_value);
  const size_t change_test = p_values.size() - 1;
  const std::vector<HolmStep> steps = Holm(p_values, options.alpha);
  size_t covariate = 0;
  bool covariate_seen = false;
  for (const HolmStep& step : steps) {
    if (step.index != change_test) {
      // The most significant covariate (steps are sorted), named only when significant.
      if (covariate_seen) continue;
      covariate_seen = true;
      covariate = step.index;
      structure.p_value = step.p_value;
      if (step.rejected) structure.covariate = series.covariate_names[step.index];
    } else if (step.rejected && split > 0) {
      structure.change_time_s = series.split_time_s[split];
    }
  }
  structure.found = steps.front().rejected;
  structure.statement =
      Statement(structure, covariate, steps.front().p_value, options.alpha, words);
  return structure;
}

}  // namespace calib
