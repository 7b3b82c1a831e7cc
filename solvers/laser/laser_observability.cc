#include <calib/core/text_format.h>
#include <calib/solvers/laser/laser_observability.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace calib {
namespace {

// Wheel radii outside this range are no real wheel's (a unit mistake).
constexpr double kSmallestWheelM = 0.005;
constexpr double kLargestWheelM = 1.0;

// Relative σ above which a parameter is called poorly determined.
constexpr double kPoorRelativeSigma = 0.05;
// Share of turning (or translating) intervals below which the log is called thin.
constexpr double kThinShare = 0.05;

}  // namespace

LaserObservability AnalyzeLaserObservability(const LaserParamMatrix& covariance,
                                             const LaserCalibration& estimate,
                                             const LaserMotionCensus& census) {
  LaserObservability report;
  const double b = estimate.odometry.wheelbase_m;
  LaserParamVector scale;
  scale << estimate.odometry.left_radius_m, estimate.odometry.right_radius_m, b, b, b, 1.0;
  const LaserParamMatrix scaled =
      scale.cwiseInverse().asDiagonal() * covariance * scale.cwiseInverse().asDiagonal();
  report.relative_sigma = scaled.diagonal().cwiseMax(0.0).cwiseSqrt();
  Eigen::SelfAdjointEigenSolver<LaserParamMatrix> eig(scaled);
  const double largest = std::max(eig.eigenvalues()(kNumLaserParams - 1), 0.0);
  const double smallest = std::max(eig.eigenvalues()(0), 0.0);
  report.weakest_direction = eig.eigenvectors().col(kNumLaserParams - 1);
  report.weakest_relative_sigma = std::sqrt(largest);
  report.condition_number = smallest > 0.0 ? largest / smallest : INFINITY;

  // Words: the components that carry 90 % of the direction, largest first.
  std::vector<int> order(kNumLaserParams);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int i, int j) {
    return std::abs(report.weakest_direction(i)) > std::abs(report.weakest_direction(j));
  });
  const double sign = report.weakest_direction(order[0]) < 0 ? -1.0 : 1.0;
  std::string words;
  double carried = 0.0;
  for (int i : order) {
    const double component = sign * report.weakest_direction(i);
    if (!words.empty())
      words += component < 0 ? " − " : " + ";
    else if (component < 0)
      words += "−";
    words += Format("%.2f·", std::abs(component)) + kLaserParamNames[i];
    carried += component * component;
    if (carried > 0.9) break;
  }
  report.weakest_description = "weakest direction " + words + " (relative σ " +
                               Format("%.2g", report.weakest_relative_sigma) +
                               ", scaled condition number " +
                               Format("%.3g", report.condition_number) + ")";

  for (int i = 0; i < kNumLaserParams; ++i) {
    if (report.relative_sigma(i) > kPoorRelativeSigma || !std::isfinite(report.relative_sigma(i))) {
      // Angles in their unit; radii and b relative to themselves, the sensor position to b.
      const ParamInfo& info = kLaserParams[i];
      const std::string unit = info.is_angle  ? std::string(" ") + info.unit
                               : i >= kLaserX ? " of b"
                                              : " relative";
      report.warnings.push_back(kLaserParamNames[i] + " is poorly determined (σ " +
                                Format("%.2g", report.relative_sigma(i)) + unit + ")");
    }
  }
  const double moving = std::max(1, census.total - census.still);
  if (census.turning() < kThinShare * moving) {
    report.warnings.push_back("few intervals turn (" + std::to_string(census.turning()) + " of " +
                              std::to_string(census.total) +
                              "): the sensor position rests on little data; drive more turns");
  }
  if (census.translating() < kThinShare * moving) {
    report.warnings.push_back("few intervals translate (" + std::to_string(census.translating()) +
                              " of " + std::to_string(census.total) +
                              "): b and the radii rest on little data; drive more arcs");
  }
  // Sizes no wheeled robot has: the wheel angles' unit is the likely cause (the fit is
  // consistent at any scale, the radii absorb it).
  const OdometryParams& odometry = estimate.odometry;
  for (const double radius : {odometry.left_radius_m, odometry.right_radius_m}) {
    if (radius < kSmallestWheelM || radius > kLargestWheelM) {
      report.warnings.push_back(
          "a wheel radius of " + Format("%.3g", 1e3 * radius) +
          " mm is not a real wheel's: are the wheel angles in radians (degrees make the radii "
          "57 times too small, encoder ticks smaller still; revolutions 6.3 times too large)?");
      break;
    }
  }
  return report;
}

}  // namespace calib
