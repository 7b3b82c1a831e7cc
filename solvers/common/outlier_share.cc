#include <calib/core/order_statistic.h>
#include <calib/solvers/common/outlier_share.h>
#include <calib/solvers/common/parallel_chunks.h>

#include <algorithm>
#include <cmath>

namespace calib {

double GrossOutlierShare(const Eigen::MatrixXd& residuals, const OutlierShareOptions& options) {
  const Eigen::Index n = residuals.rows();
  if (n == 0) return 0.0;
  constexpr double kQ20OfAbsGaussian = 0.2533;  // P(|z| < 0.2533) = 0.2.
  Eigen::VectorXd limit(residuals.cols());
  // Each column's level on its own (a selection over a million samples is a pass of its own).
  ParallelSplit(static_cast<size_t>(residuals.cols()), options.num_threads, 1,
                [&](size_t, size_t begin, size_t end) {
                  std::vector<double> a(static_cast<size_t>(n));
                  for (Eigen::Index c = begin; c < static_cast<Eigen::Index>(end); ++c) {
                    for (Eigen::Index i = 0; i < n; ++i) {
                      a[static_cast<size_t>(i)] = std::abs(residuals(i, c));
                    }
                    const double sigma = KthSmallest(&a, a.size() / 5) / kQ20OfAbsGaussian;
                    limit(c) = std::max(options.cut * sigma, options.floor);
                  }
                });
  // Counts are exact in any order: chunks.
  constexpr size_t kMinChunk = 4096;
  std::vector<Eigen::Index> gross(SplitCount(static_cast<size_t>(n), kMinChunk), 0);
  ParallelSplit(static_cast<size_t>(n), options.num_threads, kMinChunk,
                [&](size_t chunk, size_t begin, size_t end) {
                  Eigen::Index count = 0;
                  for (Eigen::Index i = begin; i < static_cast<Eigen::Index>(end); ++i) {
                    // NaN counts as gross: !(x <= limit).
                    count +=
                        !(residuals.row(i).cwiseAbs().transpose().array() <= limit.array()).all();
                  }
                  gross[chunk] = count;
                });
  Eigen::Index total = 0;
  for (const Eigen::Index g : gross) total += g;
  return static_cast<double>(total) / static_cast<double>(n);
}

}  // namespace calib
