#include <calib/core/order_statistic.h>
#include <calib/solvers/common/outlier_share.h>

#include <algorithm>
#include <cmath>

namespace calib {

double GrossOutlierShare(const Eigen::MatrixXd& residuals, const OutlierShareOptions& options) {
  const Eigen::Index n = residuals.rows();
  if (n == 0) return 0.0;
  constexpr double kQ20OfAbsGaussian = 0.2533;  // P(|z| < 0.2533) = 0.2.
  Eigen::VectorXd limit(residuals.cols());
  std::vector<double> a;  // One buffer for every column: its pages fault in once.
  a.reserve(static_cast<size_t>(n));
  for (Eigen::Index c = 0; c < residuals.cols(); ++c) {
    a.clear();
    for (Eigen::Index i = 0; i < n; ++i) a.push_back(std::abs(residuals(i, c)));
    const double sigma = KthSmallest(&a, a.size() / 5) / kQ20OfAbsGaussian;
    limit(c) = std::max(options.cut * sigma, options.floor);
  }
  Eigen::Index gross = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    // NaN counts as gross: !(x <= limit).
    if (!(residuals.row(i).cwiseAbs().transpose().array() <= limit.array()).all()) ++gross;
  }
  return static_cast<double>(gross) / static_cast<double>(n);
}

}  // namespace calib
