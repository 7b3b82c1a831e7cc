#ifndef CALIB_CORE_ORDER_STATISTIC_H_
#define CALIB_CORE_ORDER_STATISTIC_H_

#include <cstddef>
#include <vector>

namespace calib {

// The k-th smallest of `values` (k < size, 0-based): the value std::nth_element leaves at
// values[k]. Exact. Medians of the residuals are taken dozens of times per calibration, and
// nth_element's partitioning passes branch unpredictably (~30 µs for 4000 values, ~8 ms for a
// million): from 1024 values on, a sample of an eighth of them (256 to 4096) brackets the k-th
// one, a single pass without branches counts the values below the bracket and gathers those
// inside it, and only those are selected. When the bracket misses (or values are NaN), it falls
// back to nth_element over all values. The values may be reordered.
double KthSmallest(std::vector<double>* values, size_t k);

// The upper median, values[size / 2] after nth_element (KthSmallest); 0 for no values.
double UpperMedian(std::vector<double>* values);

// The permutation that sorts `values` ascending, equal values in their given order: what
// std::stable_sort of the indices by value gives (−0 equal to +0; NaN after +∞). By radix (8 or
// 11 bits a pass, passes whose digit all values share skipped): the model screen orders a dozen
// covariates per run, and the comparison sort's merges cost a tenth of its time.
std::vector<size_t> StableOrder(const std::vector<double>& values);

}  // namespace calib

#endif  // CALIB_CORE_ORDER_STATISTIC_H_
