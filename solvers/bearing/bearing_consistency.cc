#include <calib/core/se2.h>
#include <calib/solvers/bearing/bearing_consistency.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace calib {
namespace {

double MedianAbs(std::vector<double> values) {
  if (values.empty()) return 0.0;
  for (double& v : values) v = std::abs(v);
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace

double TruncatedVariance(double c) {
  const double density = std::exp(-0.5 * c * c) / std::sqrt(2.0 * M_PI);
  const double mass = std::erf(c / std::sqrt(2.0));
  return 1.0 - 2.0 * c * density / mass;
}

double RobustSigma(const std::vector<std::vector<double>>& errors) {
  std::vector<double> all;
  for (const auto& run : errors) {
    for (double e : run) all.push_back(std::abs(e));
  }
  if (all.empty()) return 0.0;
  const size_t mid = all.size() / 2;
  std::nth_element(all.begin(), all.begin() + mid, all.end());
  return 1.4826 * all[mid];
}

BearingConsistency CheckConsistency(const BearingLog& log, int half_window) {
  BearingConsistency out;
  std::vector<double> all;
  for (const BearingRun& run : log.runs) {
    const int n = static_cast<int>(run.bearings.size());
    std::vector<double> z(n, 0.0);
    for (int j = 0; j < n; ++j) {
      std::vector<int> near;
      for (int k = std::max(0, j - half_window); k <= std::min(n - 1, j + half_window); ++k) {
        if (k != j) near.push_back(k);
      }
      if (near.size() < 5) continue;
      double cs = 0.0, sn = 0.0, span = 0.0;
      for (int k : near) {
        cs += std::cos(run.bearings[k].bearing_rad), sn += std::sin(run.bearings[k].bearing_rad);
        span = std::max(span, std::abs(run.bearings[k].t_s - run.bearings[j].t_s));
      }
      const double ref = std::atan2(sn, cs);
      std::vector<bool> keep(near.size(), true);
      double a = 0.0, variance = 1.0;
      for (int pass = 0; pass < 2; ++pass) {
        Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
        Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
        int used = 0;
        for (size_t m = 0; m < near.size(); ++m) {
          if (!keep[m]) continue;
          const double x = (run.bearings[near[m]].t_s - run.bearings[j].t_s) / span;
          const Eigen::Vector3d row(1.0, x, x * x);
          normal += row * row.transpose();
          rhs += row * WrapAngle(run.bearings[near[m]].bearing_rad - ref);
          ++used;
        }
        if (used < 4) break;
        const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
        const Eigen::Vector3d coef = ldlt.solve(rhs);
        a = coef(0);
        variance = ldlt.solve(Eigen::Vector3d::UnitX())(0);
        if (pass == 1) break;
        std::vector<double> residual;
        for (size_t m = 0; m < near.size(); ++m) {
          const double x = (run.bearings[near[m]].t_s - run.bearings[j].t_s) / span;
          residual.push_back(WrapAngle(run.bearings[near[m]].bearing_rad - ref) -
                             (coef(0) + coef(1) * x + coef(2) * x * x));
        }
        std::vector<double> magnitude;
        for (double r : residual) magnitude.push_back(std::abs(r));
        std::nth_element(magnitude.begin(), magnitude.begin() + magnitude.size() / 2,
                         magnitude.end());
        const double scale = std::max(1.4826 * magnitude[magnitude.size() / 2], 1e-12);
        for (size_t m = 0; m < near.size(); ++m) keep[m] = std::abs(residual[m]) <= 3.0 * scale;
      }
      z[j] = WrapAngle(run.bearings[j].bearing_rad - ref - a) / std::sqrt(1.0 + variance);
      all.push_back(z[j]);
    }
    out.run_sigma_rad.push_back(1.4826 * MedianAbs(z));
    out.z.push_back(z);
  }
  out.sigma_rad = 1.4826 * MedianAbs(all);
  return out;
}

}  // namespace calib
