#include <calib/solvers/bearing/bearing_circle_fit.h>

#include <Eigen/Dense>
#include <algorithm>
#include <complex>
#include <limits>

namespace calib {
namespace {

using Complex = std::complex<double>;

// The period: for a trial ξ, e^{iβj} ∥ p_j = a + b·e^{−iξ·sj} reads Im(e^{−iβj}·p_j) = 0, i.e.
// [−sin βj, cos βj, −sin(ξsj + βj), cos(ξsj + βj)]·(Re a, Im a, Re b, Im b) = 0: linear and
// homogeneous. The cost is the least eigenvalue of Σ w·rowᵀrow against Σ w·|p_j|² (a generalized
// eigenproblem), so each residual counts as the sine of a bearing error and the trivial
// p ≈ 0 (b ≈ −a as ξ → 0) gains nothing; weights 1/|p_j|² make it a plain mean of sin².
struct Projection {
  const std::vector<double>* s;
  const std::vector<double>* beta;
  std::vector<double> weight;  // Empty: all ones.

  // λ and v with vᵀ(Σ w·|p|² form)v = 1.
  double Cost(double xi, Eigen::Vector4d* vector = nullptr) const {
    Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
    Eigen::Matrix4d magnitude = Eigen::Matrix4d::Zero();
    double total = 0.0;
    for (size_t j = 0; j < s->size(); ++j) {
      const double b = (*beta)[j];
      const double phase = xi * (*s)[j] + b;
      const Eigen::Vector4d row(-std::sin(b), std::cos(b), -std::sin(phase), std::cos(phase));
      const double w = weight.empty() ? 1.0 : weight[j];
      normal.selfadjointView<Eigen::Lower>().rankUpdate(row, w);
      // |a + b·z|² = |a|² + |b|² + 2·Re(conj(a)·b·z), z = e^{−iξs}.
      const double zr = w * std::cos(xi * (*s)[j]), zi = -w * std::sin(xi * (*s)[j]);
      magnitude(2, 0) += zr, magnitude(3, 1) += zr, magnitude(3, 0) -= zi, magnitude(2, 1) += zi;
      total += w;
    }
    magnitude.diagonal().setConstant(total);
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix4d> eigen(
        Eigen::Matrix4d(normal.selfadjointView<Eigen::Lower>()),
        Eigen::Matrix4d(magnitude.selfadjointView<Eigen::Lower>()));
    if (eigen.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
    if (vector != nullptr) *vector = eigen.eigenvectors().col(0);
    return eigen.eigenvalues()(0);
  }

  // dλ/dξ = vᵀ(N' − λ·M')v (Hellmann–Feynman): locates the minimum to full precision, where the
  // cost itself is flat to √ε.
  double Slope(double xi) const {
    Eigen::Vector4d v;
    const double lambda = Cost(xi, &v);
    const Complex a(v(0), v(1)), b(v(2), v(3));
    double slope = 0.0, norm = 0.0;
    for (size_t j = 0; j < s->size(); ++j) {
      const double bj = (*beta)[j];
      const double phase = xi * (*s)[j] + bj;
      const double residual = -std::sin(bj) * v(0) + std::cos(bj) * v(1) - std::sin(phase) * v(2) +
                              std::cos(phase) * v(3);
      const double d_residual = -(*s)[j] * (std::cos(phase) * v(2) + std::sin(phase) * v(3));
      const double d_magnitude =
          2.0 * (*s)[j] * std::imag(std::conj(a) * b * std::polar(1.0, -xi * (*s)[j]));
      const double w = weight.empty() ? 1.0 : weight[j];
      slope += w * (2.0 * residual * d_residual - lambda * d_magnitude);
      norm += w * std::norm(Direction(v, xi, j));
    }
    return slope / norm;
  }

  // The model direction a + b·e^{−iξs} at sample j.
  Complex Direction(const Eigen::Vector4d& v, double xi, size_t j) const {
    return Complex(v(0), v(1)) + Complex(v(2), v(3)) * std::polar(1.0, -xi * (*s)[j]);
  }
};

BearingCircle CircleFromVector(const Projection& problem, Eigen::Vector4d v, double xi) {
  // The eigenvector's sign: the model must point at the landmark, not away from it.
  double agreement = 0.0;
  for (size_t j = 0; j < problem.s->size(); ++j) {
    const Complex p = problem.Direction(v, xi, j);
    agreement += std::real(std::conj(std::polar(1.0, (*problem.beta)[j])) * p) /
                 std::max(std::abs(p), 1e-300);
  }
  if (agreement < 0.0) v = -v;
  const Complex a(v(0), v(1)), b(v(2), v(3));
  BearingCircle c;
  c.xi_q_per_m = xi;
  c.center_bearing_rad = std::arg(a);
  if (std::abs(a) == 0.0) {
    c.ratio = std::numeric_limits<double>::infinity();
    return c;
  }
  const Complex ratio = b / a;  // r·e^{iξ·s_n}.
  c.ratio = std::abs(ratio);
  c.node_m = std::arg(ratio) / xi;
  return c;
}

// The zero of the cost's slope near `xi` (Illinois regula falsi in a bracket that widens from
// `width`); `xi` itself when no sign change is found.
double SlopeRoot(const Projection& problem, double xi, double width) {
  double lo = xi - width, hi = xi + width;
  double f_lo = problem.Slope(lo), f_hi = problem.Slope(hi);
  for (int i = 0; i < 20 && f_lo * f_hi > 0.0; ++i) {
    width *= 2.0;
    lo = xi - width, hi = xi + width;
    f_lo = problem.Slope(lo), f_hi = problem.Slope(hi);
  }
  if (!(f_lo < 0.0 && f_hi > 0.0)) return xi;  // Not a minimum's bracket.
  int side = 0;
  double x = xi;
  for (int i = 0; i < 100 && hi - lo > 4e-16 * std::abs(x); ++i) {
    x = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
    const double f = problem.Slope(x);
    if (f == 0.0) return x;
    if (f < 0.0) {
      lo = x, f_lo = f;
      if (side == -1) f_hi *= 0.5;
      side = -1;
    } else {
      hi = x, f_hi = f;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    }
  }
  return x;
}

}  // namespace

double CircleRmsResidual(const BearingCircle& c, const std::vector<double>& s,
                         const std::vector<double>& beta) {
  double sum = 0.0;
  for (size_t j = 0; j < s.size(); ++j) {
    const double e = WrapAngle(beta[j] - CircleBearing(c, s[j]));
    sum += e * e;
  }
  return std::sqrt(sum / static_cast<double>(s.size()));
}

Eigen::Matrix4d CircleCovariance(const BearingCircle& c, const std::vector<double>& s,
                                 const std::vector<double>& beta) {
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  double squares = 0.0;
  for (size_t j = 0; j < s.size(); ++j) {
    const double chi = -c.xi_q_per_m * (s[j] - c.node_m);
    const double r = c.ratio;
    const double d = 1.0 + 2.0 * r * std::cos(chi) + r * r;
    const double d_chi = (r * r + r * std::cos(chi)) / d;
    const Eigen::Vector4d row(-d_chi * (s[j] - c.node_m), d_chi * c.xi_q_per_m, 1.0,
                              std::sin(chi) / d);
    normal.selfadjointView<Eigen::Lower>().rankUpdate(row);
    const double e = WrapAngle(beta[j] - CircleBearing(c, s[j]));
    squares += e * e;
  }
  const double variance = squares / std::max<double>(1.0, static_cast<double>(s.size()) - 4.0);
  const Eigen::Matrix4d full = normal.selfadjointView<Eigen::Lower>();
  return variance * full.completeOrthogonalDecomposition().pseudoInverse();
}

StatusOr<BearingCircle> FitBearingCircle(const std::vector<double>& s_m,
                                         const std::vector<double>& bearing_rad,
                                         double xi_min_per_m, double xi_max_per_m,
                                         int max_scan_samples) {
  if (s_m.size() != bearing_rad.size() || s_m.size() < 5) {
    return Status::InvalidInput("a circle needs at least 5 bearings with their s");
  }
  const auto [lo, hi] = std::minmax_element(s_m.begin(), s_m.end());
  const double span = *hi - *lo;
  if (!(span > 0.0) || !(xi_min_per_m > 0.0) || !(xi_max_per_m > xi_min_per_m)) {
    return Status::NotObservable("the bearings span no travel of the right wheel");
  }
  // Coarse scan on a subset; steps of 1/16 of a turn over the span.
  std::vector<double> s_scan, beta_scan;
  const size_t n = s_m.size();
  const size_t m = std::min(n, static_cast<size_t>(std::max(max_scan_samples, 16)));
  for (size_t i = 0; i < m; ++i) {
    const size_t j = (m == n) ? i : i * (n - 1) / (m - 1);
    s_scan.push_back(s_m[j]);
    beta_scan.push_back(bearing_rad[j]);
  }
  const Projection scan{&s_scan, &beta_scan, {}};
  double step = 2.0 * M_PI / (16.0 * span);
  step = std::max(step, (xi_max_per_m - xi_min_per_m) / 200000.0);
  std::vector<double> grid, cost;
  for (double magnitude = xi_min_per_m; magnitude <= xi_max_per_m; magnitude += step) {
    grid.push_back(magnitude);
  }
  const int half = static_cast<int>(grid.size());
  for (int i = half - 1; i >= 0; --i) grid.push_back(-grid[i]);  // −ξmax … −ξmin, ξmin … ξmax.
  std::rotate(grid.begin(), grid.begin() + half, grid.end());
  for (double xi : grid) cost.push_back(scan.Cost(xi));
  // The cost sees lines, not rays: a landmark far from the centre (pure turning) is also fitted
  // by twice the rate with r = −1, whose direction flips by π every half turn. So the deepest
  // few local minima are refined and judged by the signed bearing residual.
  std::vector<int> minima;
  for (int i = 0; i < static_cast<int>(grid.size()); ++i) {
    const bool left = i == 0 || cost[i] <= cost[i - 1];
    const bool right = i + 1 == static_cast<int>(grid.size()) || cost[i] <= cost[i + 1];
    if (left && right && std::isfinite(cost[i])) minima.push_back(i);
  }
  std::sort(minima.begin(), minima.end(), [&](int x, int y) { return cost[x] < cost[y]; });
  if (minima.size() > 6) minima.resize(6);
  if (minima.empty()) return Status::NotObservable("no period fits the bearings");

  BearingCircle best;
  double best_rms = std::numeric_limits<double>::infinity();
  for (int index : minima) {
    // Refinement on all samples, then reweighting so residuals are bearing errors.
    Projection full{&s_m, &bearing_rad, {}};
    const double start = grid[index];
    double xi = GoldenMinimum([&](double x) { return full.Cost(x); }, start - step, start + step);
    Eigen::Vector4d v;
    for (int round = 0; round < 3; ++round) {
      full.Cost(xi, &v);
      full.weight.assign(n, 1.0);
      double mean = 0.0;
      for (size_t j = 0; j < n; ++j) {
        full.weight[j] = 1.0 / std::max(std::norm(full.Direction(v, xi, j)), 1e-300);
        mean += full.weight[j] / n;
      }
      for (double& w : full.weight) w /= mean;
      xi = GoldenMinimum([&](double x) { return full.Cost(x); }, xi - 0.5 * step, xi + 0.5 * step);
    }
    xi = SlopeRoot(full, xi, 1e-6 * step);
    full.Cost(xi, &v);
    const BearingCircle circle = NormalizeCircle(CircleFromVector(full, v, xi), *lo);
    const double rms = CircleRmsResidual(circle, s_m, bearing_rad);
    if (rms < best_rms) best_rms = rms, best = circle;
  }
  return best;
}

}  // namespace calib
