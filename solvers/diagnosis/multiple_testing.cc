#include <calib/solvers/diagnosis/multiple_testing.h>

#include <algorithm>
#include <numeric>

namespace calib {

std::vector<HolmStep> Holm(const std::vector<double>& p_values, double alpha) {
  std::vector<size_t> order(p_values.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return p_values[a] < p_values[b]; });
  const size_t m = order.size();
  std::vector<HolmStep> steps(m);
  bool stopped = false;
  for (size_t rank = 0; rank < m; ++rank) {
    HolmStep& step = steps[rank];
    step.index = order[rank];
    step.p_value = p_values[step.index];
    step.level = alpha / static_cast<double>(m - rank);
    step.rejected = !stopped && step.p_value <= step.level;
    stopped = !step.rejected;
  }
  return steps;
}

}  // namespace calib
