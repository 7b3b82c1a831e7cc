#ifndef CALIB_SOLVERS_COMMON_OUTLIER_SHARE_H_
#define CALIB_SOLVERS_COMMON_OUTLIER_SHARE_H_

#include <Eigen/Core>
#include <vector>

// The share of samples that the noise of the best-fitting samples cannot explain. A robust loss
// is fitted with a noise level re-estimated from all residuals; when most samples are gross, that
// level grows with them and the inlier count says nothing. Here each residual component's noise
// level is read off the best fifth of the samples instead (σ = q₂₀(|e|)/0.2533, exact for a
// Gaussian), which stays the inliers' level up to 80 % gross samples, and a sample is gross when
// any component lies beyond `cut` such σ. The cut is wide because real residuals are not one
// Gaussian: timing errors grow with speed (a scanner picked up at the encoders' poll rate puts
// 30 % of its intervals beyond 8σ of the slow ones, 21 % beyond 12σ), while a scan matcher's
// failures are hundreds of σ off (the sample log's 5 % all lie beyond 20σ). Components whose
// residuals are all below `floor` (noise-free data) count as explained.
namespace calib {

struct OutlierShareOptions {
  double cut = 12.0;
  double floor = 1e-9;
  int num_threads = 2;  // The columns' levels side by side, the count in chunks.
};

// `residuals`: one row per sample, one column per component.
double GrossOutlierShare(const Eigen::MatrixXd& residuals, const OutlierShareOptions& options = {});

// The share beyond which a robust fit is not trusted: its estimate follows the outliers.
constexpr double kMaxTrustedOutlierShare = 0.4;

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_OUTLIER_SHARE_H_
