#include <calib/solvers/bearing/bearing_circle_fit.h>
#include <calib/solvers/bearing/bearing_text.h>
#include <calib/solvers/bearing/martinelli_run_fit.h>

#include <algorithm>
#include <complex>
#include <limits>
#include <numeric>

namespace calib {
namespace {

using Complex = std::complex<double>;

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

// The circle of one run, its period searched from a fifth of the span (less is reported later)
// to three samples per period, and no faster than |ξq| = |δR − q·δL|/(δB·B) allows with factors
// within [1/f, f].
StatusOr<BearingCircle> FitRunCircle(const CircularRunSamples& samples, double wheelbase_m,
                                     const MartinelliOptions& options, double* span) {
  const std::string name = RunName(samples.run);
  const std::vector<double>& s = samples.s_m;
  const int n = static_cast<int>(s.size());
  if (n < 8) {
    return Status::NotObservable(name + ": " + std::to_string(n) +
                                 " bearing(s); a circular run needs at least 8 to fix its period, "
                                 "node, L and k");
  }
  const auto [s_lo, s_hi] = std::minmax_element(s.begin(), s.end());
  *span = *s_hi - *s_lo;
  if (!(*span > 0.0)) {
    return Status::NotObservable(name +
                                 ": the right wheel does not move while the bearings are taken");
  }
  const double f = options.max_calibration_factor;
  const double xi_min = 2.0 * M_PI * 0.2 / *span;
  const double xi_max =
      std::max(1.5 * xi_min, std::min(2.0 * M_PI * std::max(1.0, n / 3.0) / *span,
                                      f * f * (1.0 + std::abs(samples.q)) / wheelbase_m));
  StatusOr<BearingCircle> fitted =
      FitBearingCircle(s, samples.bearing_rad, xi_min, xi_max, options.max_period_scan_samples);
  if (!fitted.ok()) return fitted.status().Prefixed(name + ": ");
  return fitted;
}

// Algorithm 1 (the node), eq. 35 (L), eq. 36 (k), as reported next to the all-sample circle.
void ReportAlgorithm1(const std::vector<double>& s, const std::vector<double>& beta,
                      const StatusOr<NodeSearch>& node, double period, MartinelliRunEstimate* run) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  run->node_algorithm1_m = node.ok() ? node->node_m : nan;
  run->spread_algorithm1_rad = node.ok() ? node->spread_rad : nan;
  run->k_mirror_points_per_m = nan;
  run->l_algorithm1_rad = nan;
  if (!node.ok()) return;
  const PeriodicBearings table(s, beta, run->xi_q_per_m);
  double beta_m1 = 0.0, beta_m2 = 0.0;
  if (table.At(node->node_m + 0.25 * period, &beta_m1) &&
      table.At(node->node_m + 0.75 * period, &beta_m2)) {
    run->k_mirror_points_per_m = KFromMirrorBearings(beta_m1, beta_m2, run->xi_q_per_m);
  }
  run->l_algorithm1_rad = 0.5 * M_PI - 0.5 * node->symmetric_sum_rad;
}

// The paper's circle: node from Algorithm 1, θC ≡ sum/2 (mod π) and |r| from eq. 36, the sign
// pair that fits the bearings.
StatusOr<BearingCircle> CircleFromAlgorithm1(const CircularRunSamples& samples,
                                             const StatusOr<NodeSearch>& node,
                                             const MartinelliRunEstimate& run,
                                             BearingCircle circle) {
  if (!node.ok() || !std::isfinite(run.k_mirror_points_per_m)) {
    return Status::NotObservable(
        RunName(samples.run) + ": " +
        (node.ok() ? std::string("the mirror points of eq. 36 fall in a gap of the bearings")
                   : node.message()) +
        "; use the all-sample refinement");
  }
  circle.node_m = node->node_m;
  const double r_abs = std::sqrt(std::max(1.0 - run.xi_q_per_m / run.k_mirror_points_per_m, 0.0));
  double best = std::numeric_limits<double>::infinity();
  BearingCircle chosen = circle;
  for (double theta : {0.5 * node->symmetric_sum_rad, 0.5 * node->symmetric_sum_rad + M_PI}) {
    for (double ratio : {r_abs, -r_abs}) {
      BearingCircle trial = circle;
      trial.center_bearing_rad = WrapAngle(theta);
      trial.ratio = ratio;
      const double rms = CircleRmsResidual(trial, samples.s_m, samples.bearing_rad);
      if (rms < best) best = rms, chosen = trial;
    }
  }
  return chosen;
}

}  // namespace

StatusOr<NodeSearch> FindNodeAlgorithm1(const std::vector<double>& s_m,
                                        const std::vector<double>& bearing_rad, double xi_q_per_m,
                                        int grid_points) {
  if (s_m.size() != bearing_rad.size() || s_m.size() < 3 || !(xi_q_per_m != 0.0) ||
      !std::isfinite(xi_q_per_m)) {
    return Status::InvalidInput("Algorithm 1 needs bearings and a non-zero ξq");
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
  if (best_cost >= 2.0)
    return Status::NotObservable("Algorithm 1 found no mirrored pairs of bearings");
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
                                                const MartinelliOptions& options,
                                                const std::vector<bool>* keep) {
  const std::string name = RunName(run.id);
  if (run.odometry.size() < 2 || run.bearings.empty()) {
    return Status::NotObservable(name + ": needs encoder samples and bearings");
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
    return Status::NotObservable(name +
                                 ": the right wheel does not turn; a circular run needs vR ≠ 0 " +
                                 "(s is the right wheel's travel)");
  }
  CircularRunSamples out;
  out.run = run.id;
  out.q = lr / rr;
  if (std::abs(out.q) > options.max_abs_q) {
    return Status::NotObservable(
        name + ": the right wheel barely turns (q = vL/vR = " + Num(out.q) +
        "); s is the right wheel's travel, so q must stay within ±" + Num(options.max_abs_q));
  }
  for (const EncoderSample& e : run.odometry) {
    const double dl = e.left_rad - first.left_rad, dr = e.right_rad - first.right_rad;
    out.q_deviation = std::max(out.q_deviation, std::abs(dl - out.q * dr) / max_right);
  }
  if (out.q_deviation > options.max_q_deviation) {
    out.circle = false;
    out.not_circle = name + " is not a circle at a fixed q = vL/vR: the wheel rotations " +
                     "depart from the ratio " + Num(out.q) + " by " +
                     Num(100.0 * out.q_deviation, 3) + "% of the right wheel's rotation (max " +
                     Num(100.0 * options.max_q_deviation, 3) + "%)";
    return out;
  }
  const double q = out.q;
  for (size_t j = 0; j < run.bearings.size(); ++j) {
    if (keep != nullptr && !(*keep)[j]) continue;
    const BearingSample& b = run.bearings[j];
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

StatusOr<MartinelliRunEstimate> FitCircularRun(const CircularRunSamples& samples,
                                               double wheelbase_m,
                                               const MartinelliOptions& options) {
  const std::string name = RunName(samples.run);
  const std::vector<double>& s = samples.s_m;
  const std::vector<double>& beta = samples.bearing_rad;
  double span = 0.0;
  CALIB_ASSIGN_OR_RETURN(const BearingCircle fitted,
                         FitRunCircle(samples, wheelbase_m, options, &span));
  const double xi_q = fitted.xi_q_per_m;
  const double period = 2.0 * M_PI / std::abs(xi_q);

  MartinelliRunEstimate run;
  run.run = samples.run;
  run.q = samples.q;
  run.num_bearings = static_cast<int>(s.size());
  run.xi_q_per_m = xi_q;
  run.periods_covered = span / period;
  const double r = std::abs(fitted.ratio);
  run.parallax = std::isfinite(r) ? std::min(r, 1.0 / r) : 0.0;
  if (!(run.parallax >= options.min_parallax)) {
    return Status::NotObservable(
        name + ": the landmark direction barely changes with respect to the robot's turning " +
        "(parallax " + Num(run.parallax, 3) + " < " + Num(options.min_parallax, 3) +
        "): the landmark is too far from, or too close to, the centre of the circle, so its " +
        "bearing carries no node");
  }
  if (run.periods_covered < options.min_periods) {
    return Status::NotObservable(name + ": the bearings cover " + Num(run.periods_covered, 3) +
                                 " of a period of β(s) (2π/|ξq| ≈ " + Num(period) +
                                 " m of right-wheel travel; they span " + Num(span) +
                                 " m); at least " + Num(options.min_periods, 3) +
                                 " of a period (one loop) is needed");
  }
  // With bearings missing over much of the circle (a narrow field of view) Algorithm 1 may find
  // no mirrored pairs; the all-sample circle does not need it.
  const StatusOr<NodeSearch> node = FindNodeAlgorithm1(s, beta, xi_q, options.node_grid_points);
  ReportAlgorithm1(s, beta, node, period, &run);

  BearingCircle circle = fitted;
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
    CALIB_ASSIGN_OR_RETURN(circle, CircleFromAlgorithm1(samples, node, run, circle));
  }
  run.circle = circle;
  run.node_m = circle.node_m;
  run.k_per_m = CircleK(circle);
  run.rms_residual_rad = CircleRmsResidual(circle, s, beta);
  run.circle_covariance = CircleCovariance(circle, s, beta);
  // Provisional L (mod π, in [0, π)); the branch is chosen once ψ is known.
  run.l_rad = CircleLModPi(circle);
  return run;
}

}  // namespace calib
