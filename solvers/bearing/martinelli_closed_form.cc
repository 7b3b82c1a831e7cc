#include <calib/solvers/bearing/martinelli_closed_form.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numeric>
#include <sstream>

#include <calib/core/bearing/bearing_log_io.h>

namespace calib {
namespace {

using Complex = std::complex<double>;

std::string Num(double value, int digits = 4) {
  std::ostringstream out;
  out.precision(digits);
  out << value;
  return out.str();
}

std::string RunName(int id) { return "run " + std::to_string(id); }

// Minimises f on [lo, hi] by golden-section search.
template <typename F>
double GoldenMinimum(F f, double lo, double hi, int iterations = 80) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < iterations && hi - lo > 1e-15 * (1.0 + std::abs(lo)); ++i) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - g * (hi - lo), f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + g * (hi - lo), f2 = f(x2);
    }
  }
  return f1 < f2 ? x1 : x2;
}

// ---------------------------------------------------------------------------------------------
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

// ---------------------------------------------------------------------------------------------
// β(s) by linear interpolation on the samples sorted by s and unwrapped, extended periodically.
class PeriodicBearings {
 public:
  PeriodicBearings(const std::vector<double>& s, const std::vector<double>& beta, double xi)
      : period_(2.0 * M_PI / std::abs(xi)) {
    std::vector<size_t> order(s.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return s[a] < s[b]; });
    for (size_t i : order) {
      const double value =
          unwrapped_.empty() ? beta[i] : unwrapped_.back() + WrapAngle(beta[i] - last_beta_);
      s_.push_back(s[i]);
      unwrapped_.push_back(value);
      last_beta_ = beta[i];
    }
    closing_ = unwrapped_.back() + WrapAngle(beta[order.front()] - last_beta_);
  }

  double period() const { return period_; }
  double origin() const { return s_.front(); }

  bool At(double x, double* beta) const {
    const double max_gap = 0.1 * period_;
    double local = std::fmod(x - s_.front(), period_);
    if (local < 0.0) local += period_;
    x = s_.front() + local;
    if (x <= s_.back()) {
      const size_t i = std::upper_bound(s_.begin(), s_.end(), x) - s_.begin();
      if (i == s_.size()) {  // x == s_.back().
        *beta = unwrapped_.back();
        return true;
      }
      if (s_[i] - s_[i - 1] > max_gap) return false;
      const double f = (x - s_[i - 1]) / (s_[i] - s_[i - 1]);
      *beta = unwrapped_[i - 1] + f * (unwrapped_[i] - unwrapped_[i - 1]);
      return true;
    }
    const double end = s_.front() + period_;  // Closes the period with the first sample.
    if (end - s_.back() > max_gap) return false;
    const double f = (x - s_.back()) / (end - s_.back());
    *beta = unwrapped_.back() + f * (closing_ - unwrapped_.back());
    return true;
  }

 private:
  double period_;
  std::vector<double> s_;
  std::vector<double> unwrapped_;
  double last_beta_ = 0.0;
  double closing_ = 0.0;
};

// The mean resultant of β(sj) + β(2s_c − sj) over the samples: 1 at a node on noise-free data.
Complex SymmetricSum(const PeriodicBearings& table, const std::vector<double>& s,
                     const std::vector<double>& beta, double s_c, int* pairs) {
  Complex sum(0.0, 0.0);
  int n = 0;
  for (size_t j = 0; j < s.size(); ++j) {
    double mirrored = 0.0;
    if (!table.At(2.0 * s_c - s[j], &mirrored)) continue;
    sum += std::polar(1.0, beta[j] + mirrored);
    ++n;
  }
  if (pairs != nullptr) *pairs = n;
  return n > 0 ? sum / static_cast<double>(n) : Complex(0.0, 0.0);
}

double RmsResidual(const BearingCircle& c, const std::vector<double>& s,
                   const std::vector<double>& beta) {
  double sum = 0.0;
  for (size_t j = 0; j < s.size(); ++j) {
    const double e = WrapAngle(beta[j] - CircleBearing(c, s[j]));
    sum += e * e;
  }
  return std::sqrt(sum / static_cast<double>(s.size()));
}

// Covariance of (ξq, s_n, θC, r) from the bearing residuals: σ̂²(JᵀJ)⁻¹ with J the derivatives of
// β = θC + atan2(r sin χ, 1 + r cos χ), χ = −ξq(s − s_n).
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

// The representative of x modulo `period` nearest to `target`.
double NearestModulo(double x, double period, double target) {
  return x + period * std::round((target - x) / period);
}

// Per-run part of the closed form (§6–7).
StatusOr<MartinelliRunEstimate> FitRun(const CircularRunSamples& samples, double wheelbase_m,
                                       const MartinelliOptions& options) {
  const std::string name = RunName(samples.run);
  const std::vector<double>& s = samples.s_m;
  const std::vector<double>& beta = samples.bearing_rad;
  const int n = static_cast<int>(s.size());
  if (n < 8) {
    return Status::Error(name + ": " + std::to_string(n) +
                         " bearing(s); a circular run needs at least 8 to fix its period, node, "
                         "L and k");
  }
  const auto [s_lo, s_hi] = std::minmax_element(s.begin(), s.end());
  const double span = *s_hi - *s_lo;
  if (!(span > 0.0)) {
    return Status::Error(name + ": the right wheel does not move while the bearings are taken");
  }
  // Periods from a fifth of the span (less is reported below) to three samples per period, and
  // no faster than |ξq| = |δR − q·δL|/(δB·B) allows with factors within [1/f, f].
  const double f = options.max_calibration_factor;
  const double xi_min = 2.0 * M_PI * 0.2 / span;
  const double xi_max =
      std::max(1.5 * xi_min, std::min(2.0 * M_PI * std::max(1.0, n / 3.0) / span,
                                      f * f * (1.0 + std::abs(samples.q)) / wheelbase_m));
  StatusOr<BearingCircle> fitted =
      FitBearingCircle(s, beta, xi_min, xi_max, options.max_period_scan_samples);
  if (!fitted.ok()) return Status::Error(name + ": " + fitted.message());
  const double xi_q = fitted->xi_q_per_m;
  const double period = 2.0 * M_PI / std::abs(xi_q);

  MartinelliRunEstimate run;
  run.run = samples.run;
  run.q = samples.q;
  run.num_bearings = n;
  run.xi_q_per_m = xi_q;
  run.periods_covered = span / period;
  const double r = std::abs(fitted->ratio);
  run.parallax = std::isfinite(r) ? std::min(r, 1.0 / r) : 0.0;
  if (!(run.parallax >= options.min_parallax)) {
    return Status::Error(
        name + ": the landmark direction barely changes with respect to the robot's turning " +
        "(parallax " + Num(run.parallax, 3) + " < " + Num(options.min_parallax, 3) +
        "): the landmark is too far from, or too close to, the centre of the circle, so its " +
        "bearing carries no node");
  }

  if (run.periods_covered < options.min_periods) {
    return Status::Error(name + ": the bearings cover " + Num(run.periods_covered, 3) +
                         " of a period of β(s) (2π/|ξq| ≈ " + Num(period) +
                         " m of right-wheel travel; they span " + Num(span) + " m); at least " +
                         Num(options.min_periods, 3) + " of a period (one loop) is needed");
  }
  // Algorithm 1 (the node), eq. 35 (L), eq. 36 (k). With bearings missing over much of the circle
  // (a narrow field of view) it may find no mirrored pairs; the all-sample circle does not need it.
  const StatusOr<NodeSearch> node = FindNodeAlgorithm1(s, beta, xi_q, options.node_grid_points);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  run.node_algorithm1_m = node.ok() ? node->node_m : nan;
  run.spread_algorithm1_rad = node.ok() ? node->spread_rad : nan;
  run.k_mirror_points_per_m = nan;
  run.l_algorithm1_rad = nan;
  if (node.ok()) {
    const PeriodicBearings table(s, beta, xi_q);
    double beta_m1 = 0.0, beta_m2 = 0.0;
    if (table.At(node->node_m + 0.25 * period, &beta_m1) &&
        table.At(node->node_m + 0.75 * period, &beta_m2)) {
      run.k_mirror_points_per_m = KFromMirrorBearings(beta_m1, beta_m2, xi_q);
    }
    run.l_algorithm1_rad = 0.5 * M_PI - 0.5 * node->symmetric_sum_rad;
  }

  BearingCircle circle = *fitted;
  if (options.refine_with_all_samples) {
    // The fitted circle, with its node the one Algorithm 1 found (nodes repeat every π/|ξq|).
    if (node.ok()) {
      const double shift = NearestModulo(circle.node_m, 0.5 * period, node->node_m) - circle.node_m;
      if (std::fmod(std::abs(std::round(shift / (0.5 * period))), 2.0) == 1.0) {
        circle.ratio = -circle.ratio;
      }
      circle.node_m += shift;
    }
  } else {
    if (!node.ok() || !std::isfinite(run.k_mirror_points_per_m)) {
      return Status::Error(name + ": " +
                           (node.ok() ? std::string("the mirror points of eq. 36 fall in a gap of "
                                                    "the bearings")
                                      : node.message()) +
                           "; use the all-sample refinement");
    }
    // θC ≡ sum/2 (mod π) and |r| from eq. 36; the sign pair that fits the bearings.
    circle.node_m = node->node_m;
    const double r_abs = std::sqrt(std::max(1.0 - xi_q / run.k_mirror_points_per_m, 0.0));
    double best = std::numeric_limits<double>::infinity();
    for (double theta : {0.5 * node->symmetric_sum_rad, 0.5 * node->symmetric_sum_rad + M_PI}) {
      for (double ratio : {r_abs, -r_abs}) {
        BearingCircle trial = circle;
        trial.center_bearing_rad = WrapAngle(theta);
        trial.ratio = ratio;
        const double rms = RmsResidual(trial, s, beta);
        if (rms < best) best = rms, circle = trial;
      }
    }
  }
  run.circle = circle;
  run.node_m = circle.node_m;
  run.k_per_m = CircleK(circle);
  run.rms_residual_rad = RmsResidual(circle, s, beta);
  run.circle_covariance = CircleCovariance(circle, s, beta);
  // Provisional L (mod π, in [0, π)); the branch is chosen once ψ is known.
  run.l_rad = CircleLModPi(circle);
  return run;
}

}  // namespace

StatusOr<BearingCircle> FitBearingCircle(const std::vector<double>& s_m,
                                         const std::vector<double>& bearing_rad,
                                         double xi_min_per_m, double xi_max_per_m,
                                         int max_scan_samples) {
  if (s_m.size() != bearing_rad.size() || s_m.size() < 5) {
    return Status::Error("a circle needs at least 5 bearings with their s");
  }
  const auto [lo, hi] = std::minmax_element(s_m.begin(), s_m.end());
  const double span = *hi - *lo;
  if (!(span > 0.0) || !(xi_min_per_m > 0.0) || !(xi_max_per_m > xi_min_per_m)) {
    return Status::Error("the bearings span no travel of the right wheel");
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
  if (minima.empty()) return Status::Error("no period fits the bearings");

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
    const double rms = RmsResidual(circle, s_m, bearing_rad);
    if (rms < best_rms) best_rms = rms, best = circle;
  }
  return best;
}

StatusOr<NodeSearch> FindNodeAlgorithm1(const std::vector<double>& s_m,
                                        const std::vector<double>& bearing_rad, double xi_q_per_m,
                                        int grid_points) {
  if (s_m.size() != bearing_rad.size() || s_m.size() < 3 || !(xi_q_per_m != 0.0) ||
      !std::isfinite(xi_q_per_m)) {
    return Status::Error("Algorithm 1 needs bearings and a non-zero ξq");
  }
  const PeriodicBearings table(s_m, bearing_rad, xi_q_per_m);
  const double half = 0.5 * table.period();
  const int g = std::max(grid_points, 8);
  const double h = half / g;
  // Spread: 1 − mean resultant length (monotone in the circular standard deviation).
  const auto spread = [&](double s_c) {
    int pairs = 0;
    const double resultant = std::abs(SymmetricSum(table, s_m, bearing_rad, s_c, &pairs));
    return pairs >= 3 ? 1.0 - resultant : 2.0;
  };
  double best = table.origin(), best_cost = std::numeric_limits<double>::infinity();
  for (int i = 0; i < g; ++i) {
    const double s_c = table.origin() + i * h;
    const double cost = spread(s_c);
    if (cost < best_cost) best_cost = cost, best = s_c;
  }
  if (best_cost >= 2.0) return Status::Error("Algorithm 1 found no mirrored pairs of bearings");
  // Below the grid step.
  double node = GoldenMinimum(spread, best - h, best + h);
  node = table.origin() + std::fmod(node - table.origin() + half, half);
  NodeSearch result;
  result.node_m = node;
  const Complex mean = SymmetricSum(table, s_m, bearing_rad, node, &result.pairs);
  result.spread_rad = std::sqrt(std::max(0.0, -2.0 * std::log(std::abs(mean))));
  result.symmetric_sum_rad = std::arg(mean);
  return result;
}

StatusOr<CircularRunSamples> ExtractCircularRun(const BearingRun& run, double wheel_radius_m,
                                                const MartinelliOptions& options) {
  const std::string name = RunName(run.id);
  if (run.odometry.size() < 2 || run.bearings.empty()) {
    return Status::Error(name + ": needs encoder samples and bearings");
  }
  const EncoderSample& first = run.odometry.front();
  double lr = 0.0, rr = 0.0, max_right = 0.0;
  for (const EncoderSample& e : run.odometry) {
    const double dl = e.left_rad - first.left_rad, dr = e.right_rad - first.right_rad;
    lr += dl * dr;
    rr += dr * dr;
    max_right = std::max(max_right, std::abs(dr));
  }
  if (!(max_right * wheel_radius_m > 1e-9)) {
    return Status::Error(name + ": the right wheel does not turn; a circular run needs vR ≠ 0 " +
                         "(s is the right wheel's travel)");
  }
  CircularRunSamples out;
  out.run = run.id;
  out.q = lr / rr;
  if (std::abs(out.q) > options.max_abs_q) {
    return Status::Error(name + ": the right wheel barely turns (q = vL/vR = " + Num(out.q) +
                         "); s is the right wheel's travel, so q must stay within ±" +
                         Num(options.max_abs_q));
  }
  for (const EncoderSample& e : run.odometry) {
    const double dl = e.left_rad - first.left_rad, dr = e.right_rad - first.right_rad;
    out.q_deviation = std::max(out.q_deviation, std::abs(dl - out.q * dr) / max_right);
  }
  if (out.q_deviation > options.max_q_deviation) {
    return Status::Error(name + " is not a circle at a fixed q = vL/vR: the wheel rotations " +
                         "depart from the ratio " + Num(out.q) + " by " +
                         Num(100.0 * out.q_deviation, 3) + "% of the right wheel's rotation (max " +
                         Num(100.0 * options.max_q_deviation, 3) + "%)");
  }
  const double q = out.q;
  for (const BearingSample& b : run.bearings) {
    double left = 0.0, right = 0.0;
    InterpolateWheelAngles(run.odometry, b.t_s, &left, &right);
    const double dl = left - first.left_rad, dr = right - first.right_rad;
    // With αL = q·αR both wheels measure the progress; their least-squares combination is less
    // noisy than the right wheel alone.
    const double progress = options.combine_wheels ? (dr + q * dl) / (1.0 + q * q) : dr;
    out.s_m.push_back(wheel_radius_m * progress);
    out.bearing_rad.push_back(b.bearing_rad);
  }
  return out;
}

StatusOr<MartinelliEstimate> MartinelliClosedForm(const BearingLog& log,
                                                  const MartinelliOptions& options) {
  Status status = ValidateBearingLog(log);
  if (!status.ok()) return status;
  const std::string source = log.source.empty() ? "bearing log" : log.source;
  const double wheelbase = log.meta.wheelbase_m;
  MartinelliEstimate estimate;

  for (const BearingRun& run : log.runs) {
    StatusOr<CircularRunSamples> samples =
        ExtractCircularRun(run, log.meta.wheel_radius_m, options);
    if (!samples.ok()) {
      const bool non_circular = samples.message().find("not a circle") != std::string::npos;
      if (options.skip_non_circular_runs && non_circular) {
        estimate.skipped_runs.push_back(run.id);
        continue;
      }
      return Status::Error(source + ": " + samples.message());
    }
    StatusOr<MartinelliRunEstimate> fitted = FitRun(*samples, wheelbase, options);
    if (!fitted.ok()) return Status::Error(source + ": " + fitted.message());
    estimate.runs.push_back(*fitted);
  }

  // At least three distinct q (§7).
  std::vector<double> distinct;
  for (const MartinelliRunEstimate& run : estimate.runs) {
    const bool seen = std::any_of(distinct.begin(), distinct.end(), [&](double q) {
      return std::abs(q - run.q) < options.min_q_separation;
    });
    if (!seen) distinct.push_back(run.q);
  }
  if (distinct.size() < 3) {
    std::string qs;
    for (const MartinelliRunEstimate& run : estimate.runs) {
      qs += (qs.empty() ? "" : ", ") + RunName(run.run) + ": q = " + Num(run.q, 3);
    }
    return Status::Error(source + ": the closed form needs circular runs with at least 3 " +
                         "distinct wheel-speed ratios q = vL/vR (differing by ≥ " +
                         Num(options.min_q_separation, 3) + "); found " +
                         std::to_string(distinct.size()) + (qs.empty() ? "" : " (" + qs + ")"));
  }

  // ξ and δ from ξq = ξ − ξδ·q (eq. 11), least squares over the runs.
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  // Weighted by each ξq's variance: a long run at q near 1/δ pins ξ(1 − qδ) far better than the
  // short ones, which is what makes δ precise (the residual noise floor keeps weights bounded).
  for (const MartinelliRunEstimate& run : estimate.runs) {
    const double variance =
        run.circle_covariance(0, 0) + std::pow(1e-9 * std::abs(run.xi_q_per_m), 2) + 1e-300;
    const Eigen::Vector2d row(1.0, -run.q);
    normal += row * row.transpose() / variance;
    rhs += row * run.xi_q_per_m / variance;
  }
  const Eigen::Vector2d xi_xidelta = normal.ldlt().solve(rhs);
  BearingParams& p = estimate.params;
  p.xi_per_m = xi_xidelta(0);
  p.delta = xi_xidelta(1) / xi_xidelta(0);

  // φ, ψ, η. The direction of the centre of rotation from the sensor, θC + φ + ψ in the robot
  // frame, is that of g = (−ξq cos φ, ηq − ξq sin φ)·sign(ξq); its cross product with the measured
  // direction vanishes:
  //   (1 + qδ)·(cos θC·X1 − sin θC·X2) + ξq·(sin θC·Y1 + cos θC·Y2) = 0,
  // with X = η·(cos(φ+ψ), sin(φ+ψ)), Y = (cos ψ, sin ψ): linear and homogeneous, so three runs
  // give X and Y up to a common factor, fixed by |Y| = 1 and the sign of the dot product. This is
  // §7's system ηx·Ψ1 + ηy = f_q with Ψ1 = tan(ψ − L), multiplied through by cos(ψ − L)(1 + qδ),
  // where f_q must read ξ(1 − qδ)/(1 + qδ) (the report prints it inverted).
  const int runs = static_cast<int>(estimate.runs.size());
  Eigen::MatrixXd mx(runs, 2), my(runs, 2);
  Eigen::Vector2d x, y;
  double eta_guess = 0.0, phi_guess = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < runs; ++i) {
      const MartinelliRunEstimate& run = estimate.runs[i];
      const double theta = run.circle.center_bearing_rad;
      const double one_plus = 1.0 + run.q * p.delta;
      const double xi_q = XiQ(p.xi_per_m, p.delta, run.q);
      // Rows scaled to unit |g| so each run weighs by its angle, not by its ξq.
      double norm = 1.0;
      if (pass > 0) {
        const double eta_q = eta_guess * one_plus;
        norm = std::sqrt(std::max(
            xi_q * xi_q + eta_q * eta_q - 2.0 * xi_q * eta_q * std::sin(phi_guess), 1e-300));
      }
      mx.row(i) << one_plus * std::cos(theta) / norm, -one_plus * std::sin(theta) / norm;
      my.row(i) << xi_q * std::sin(theta) / norm, xi_q * std::cos(theta) / norm;
    }
    const Eigen::Matrix2d pxx = mx.transpose() * mx;
    const double scale = (mx.transpose() * mx).trace() + (my.transpose() * my).trace();
    if (!(std::abs(pxx.determinant()) > 1e-12 * pxx.trace() * pxx.trace())) {
      return Status::Error(source + ": the runs see their centres of rotation in one direction, " +
                           "so η and φ cannot be separated: the sensor sits on the line of the " +
                           "wheel axle (φ ≈ ±90°), where η is not observable from circles, or " +
                           "the runs are too alike");
    }
    const Eigen::Matrix2d gain = pxx.inverse() * (mx.transpose() * my);
    const Eigen::Matrix2d schur = my.transpose() * my - (my.transpose() * mx) * gain;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(schur);
    if (!(eigen.eigenvalues()(1) > 1e-12 * scale)) {
      return Status::Error(source + ": the runs do not determine ψ (degenerate geometry)");
    }
    y = eigen.eigenvectors().col(0);
    x = -gain * y;
    double sign = 0.0;
    for (int i = 0; i < runs; ++i) {
      const MartinelliRunEstimate& run = estimate.runs[i];
      const double theta = run.circle.center_bearing_rad;
      const double xi_q = XiQ(p.xi_per_m, p.delta, run.q);
      const double dot =
          -xi_q * (std::cos(theta) * y(0) - std::sin(theta) * y(1)) +
          (1.0 + run.q * p.delta) * (std::sin(theta) * x(0) + std::cos(theta) * x(1));
      sign += xi_q < 0.0 ? -dot : dot;
    }
    if (sign < 0.0) x = -x, y = -y;
    eta_guess = x.norm();
    p.psi_rad = std::atan2(y(1), y(0));
    p.phi_rad = WrapAngle(std::atan2(x(1), x(0)) - p.psi_rad);
    phi_guess = p.phi_rad;
  }
  p.eta_per_m = x.norm();
  estimate.eta_x_per_m = p.eta_per_m * std::cos(p.phi_rad);
  estimate.eta_y_per_m = p.eta_per_m * std::sin(p.phi_rad);

  // Per run: L on its defined branch, A0, V0 (eq. 14 at s = 0), c (eq. 21) and its S_w (eq. 26),
  // then μ0, γ0 by inverting eqs. 13 and 15.
  for (MartinelliRunEstimate& run : estimate.runs) {
    const double xi_q = run.xi_q_per_m;
    const double eta_q = EtaQ(p.eta_per_m, p.delta, run.q);
    const double xi_q_model = XiQ(p.xi_per_m, p.delta, run.q);
    const double l_model = p.psi_rad - std::atan(Psi1(p.phi_rad, eta_q, xi_q_model));
    run.l_rad = NearestModulo(run.l_rad, M_PI, l_model);
    run.l_algorithm1_rad = NearestModulo(run.l_algorithm1_rad, M_PI, l_model);
    CircleState(run.circle, 0.0, &run.a0, &run.v0);
    run.c_rad = CFromKV(run.k_per_m, run.v0, xi_q);
    const double base = 0.5 * M_PI - xi_q * run.node_m;
    for (int i = 0; i < 2; ++i) {
      const double c = (i == 0 ? 1.0 : -1.0) * base;
      run.c_candidates_rad[i] = c - M_PI * std::ceil(c / M_PI - 0.5);
    }
    // S_w: c + S_w·ξq·s_n ≡ π/2 (mod π).
    const auto miss = [&](int s_w) {
      const double e = std::fmod(run.c_rad + s_w * xi_q * run.node_m - 0.5 * M_PI, M_PI);
      return std::min(std::abs(e), M_PI - std::abs(e));
    };
    run.s_w = miss(1) <= miss(-1) ? 1 : -1;
    GammaMuFromState(run.a0, run.v0, p.phi_rad, eta_q, xi_q, &run.gamma0_rad, &run.mu0);
    run.gamma0_rad = WrapAngle(run.gamma0_rad);
    if (!std::isfinite(run.mu0) || !std::isfinite(run.gamma0_rad) || !(run.mu0 > 0.0)) {
      // Eqs. 13 and 15 are singular (cos φ = 0, ηq = 0, ...): place the landmark directly. In
      // the robot frame at s = 0 it sits at ρ·[(0, ηq/ξq) + g·r·e^{iξq·s_n}] with the centre's
      // offset from the sensor g = (−cos φ, ηq/ξq − sin φ).
      const Complex center(0.0, eta_q / xi_q);
      const Complex offset(-std::cos(p.phi_rad), eta_q / xi_q - std::sin(p.phi_rad));
      const Complex landmark =
          center + offset * run.circle.ratio * std::polar(1.0, xi_q * run.circle.node_m);
      run.mu0 = 1.0 / std::abs(landmark);
      run.gamma0_rad = WrapAngle(p.phi_rad - std::arg(-landmark));
    }
  }

  if (log.meta.initial_distance) {
    const InitialDistance& d = *log.meta.initial_distance;
    const auto run = std::find_if(estimate.runs.begin(), estimate.runs.end(),
                                  [&](const MartinelliRunEstimate& r) { return r.run == d.run; });
    if (run == estimate.runs.end()) {
      return Status::Error(source + ": the initial distance is given for " + RunName(d.run) +
                           ", which is not a circular run used by the closed form");
    }
    // ρ = μ0·D0 (end of §7).
    estimate.metric = MetricParams(p, run->mu0 * d.meters, wheelbase);
    estimate.has_metric = true;
  }
  return estimate;
}

}  // namespace calib
