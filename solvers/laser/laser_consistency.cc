#include <calib/core/text_format.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/diagnosis/multiple_testing.h>
#include <calib/solvers/laser/laser_consistency.h>
#include <calib/solvers/laser/laser_consistency_terms.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>

namespace calib {
namespace {

using consistency_internal::AutomaticLags;
using consistency_internal::BartlettAhead;
using consistency_internal::BartlettCentred;
using consistency_internal::ComputeTerms;
using consistency_internal::IntervalTerms;
using consistency_internal::kMinChunkIntervals;
using consistency_internal::LogTerms;
using consistency_internal::ScoreLongRun;
using consistency_internal::TermsVector;
using consistency_internal::Vector6;

struct Window {
  int log = 0;
  std::string kind;
  int first = 0, last = 0;
};

// Intervals k of `log` within [w.first, w.last] that count, and their difference h_k.
template <typename Difference>
double Term(const TermsVector& t, const Window& w, long k, Difference difference) {
  if (k < w.first || k > w.last || !t[k].counted) return 0.0;
  return difference(t[k]);
}

// σ² of the timing at a cut k of the window, where a counted interval borders one that is not
// (window ends, excluded intervals): the wheel rotation of a misplaced stamp, rate × f·period,
// the rate the smaller of the two sides' (a rest on either side makes it vanish). 0 elsewhere.
template <typename Predicted>
double CutVariance(const LaserConsistencyOptions& options, const LogTerms& log, const Window& w,
                   long k, Predicted predicted) {
  const TermsVector& t = log.terms;
  const std::vector<LaserInterval>& in = *log.intervals;
  const auto counted = [&](long i) { return i >= w.first && i <= w.last && t[i].counted; };
  if (counted(k - 1) == counted(k)) return 0.0;
  // The counted side always exists; the other one unless beyond the log or across a gap.
  const long inside = counted(k) ? k : k - 1;
  const long outside = counted(k) ? k - 1 : k;
  const bool continuous =
      outside >= 0 && outside < static_cast<long>(t.size()) && !in[std::max(k, 0L)].gap_before;
  const auto rate = [&](long i) { return std::abs(predicted(t[i])) / in[i].duration_s; };
  double period = in[inside].duration_s;
  double speed = rate(inside);
  if (continuous) {
    speed = std::min(speed, rate(outside));
    period = (period + in[outside].duration_s) / 2.0;
  }
  const double sigma = options.end_timing_fraction * speed * period;
  return sigma * sigma;
}

}  // namespace
namespace {

// Whole runs (between gaps), then the stretches of motion between two rests of a run that hold
// at least the minimum of inliers and not nearly all of the run's motion (else the run says it).
std::vector<Window> FindWindows(const std::vector<LogTerms>& logs, int min_intervals) {
  std::vector<Window> windows, between_rests;
  for (size_t d = 0; d < logs.size(); ++d) {
    const TermsVector& t = logs[d].terms;
    const std::vector<LaserInterval>& in = *logs[d].intervals;
    const int size = static_cast<int>(t.size());
    for (int a = 0; a < size;) {
      // The run [a, b] up to the next gap, and its counted intervals, all and in motion.
      int b = a, counted = 0, moving = 0;
      for (;; ++b) {
        counted += t[b].counted;
        moving += t[b].counted && !t[b].still;
        if (b + 1 == size || in[b + 1].gap_before) break;
      }
      if (counted >= min_intervals) windows.push_back(Window{static_cast<int>(d), "run", a, b});
      for (int s = a + 1; s < b; ++s) {
        if (!t[s - 1].still || t[s].still) continue;
        int e = s, n = t[s].counted;
        while (e + 1 <= b && !t[e + 1].still) n += t[++e].counted;
        if (e < b && n >= min_intervals && n < 0.9 * moving) {
          between_rests.push_back(Window{static_cast<int>(d), "between rests", s, e});
        }
        s = e;
      }
      a = b + 1;
    }
  }
  windows.insert(windows.end(), between_rests.begin(), between_rests.end());
  return windows;
}

// What every total needs beyond its window: the covariance given, the map A from an interval's
// score to its influence (IntervalTerms::score), the long-run covariance of the estimate's
// influence, the parameters that moved, the Bartlett lag.
struct Context {
  const LaserConsistencyOptions* options = nullptr;
  const LaserParamMatrix* covariance = nullptr;
  const LaserParamMatrix* influence_map = nullptr;                 // A.
  LaserParamMatrix influence_long_run = LaserParamMatrix::Zero();  // At `lag`.
  Vector6 free = Vector6::Ones();                                  // 0 for parameters held fixed.
  int lag = 1;
};

// One quantity's sums over a window's counted intervals k (h_k its difference): the totals,
// Σ h_k² + 2Σ_{j≥1} w_j h_k h_{k+j}, Σ h_k Σ_{|j|≤L} w_j g_{k+j}, and the cuts' timing σ².
struct QuantitySums {
  double predicted = 0.0, measured = 0.0, v_hh = 0.0, ends = 0.0;
  Vector6 v_gh = Vector6::Zero();
  QuantitySums& operator+=(const QuantitySums& o) {
    predicted += o.predicted;
    measured += o.measured;
    v_hh += o.v_hh;
    ends += o.ends;
    v_gh += o.v_gh;
    return *this;
  }
};

// h_k of a window's counted intervals (0 elsewhere), and g_k over the whole log (0 beyond it).
template <typename Difference>
struct DifferenceAt {
  const TermsVector* t;
  const Window* w;
  Difference difference;
  double operator()(long k) const { return Term(*t, *w, k, difference); }
};
struct ScoreAt {
  const TermsVector* t;
  Vector6 operator()(long k) const {
    return k >= 0 && k < static_cast<long>(t->size()) ? (*t)[k].Score() : Vector6::Zero().eval();
  }
};

// One quantity's sums over a chunk of a window's intervals, one interval a Step: its running
// Bartlett sums start at the chunk's first interval.
template <typename Difference, typename Predicted>
class QuantityPass {
 public:
  QuantityPass(const Context& c, const LogTerms& log, const Window& w, long begin,
               Difference difference, Predicted predicted)
      : c_(c),
        log_(log),
        w_(w),
        difference_(difference),
        predicted_(predicted),
        h_ahead_(DifferenceAt<Difference>{&log.terms, &w, difference}, c.lag, begin),
        g_around_(ScoreAt{&log.terms}, c.lag, begin) {}

  void Step(long k) {
    sums_.ends += CutVariance(*c_.options, log_, w_, k, predicted_);
    const IntervalTerms& t = log_.terms[k];
    if (t.counted) {
      const double h = difference_(t);
      sums_.predicted += predicted_(t);
      sums_.measured += predicted_(t) + h;
      sums_.v_hh += h * h + 2.0 * h * h_ahead_.value();
      sums_.v_gh += h * g_around_.value();
    }
    h_ahead_.Advance();
    g_around_.Advance();
  }
  const QuantitySums& sums() const { return sums_; }

 private:
  const Context& c_;
  const LogTerms& log_;
  const Window& w_;
  Difference difference_;
  Predicted predicted_;
  BartlettAhead<double, DifferenceAt<Difference>> h_ahead_;
  BartlettCentred<Vector6, ScoreAt> g_around_;
  QuantitySums sums_;
};

// One quantity over one window from its sums. `g_pred` and `g_meas` are the gradients of the
// window's predicted and measured totals.
LaserConsistencyTotal Total(const Context& c, const QuantitySums& s, const Vector6& g_pred,
                            const Vector6& g_meas) {
  LaserConsistencyTotal total;
  total.predicted = s.predicted;
  total.measured = s.measured;
  // d_k = 1[k∈w]·h_k + Gᵀψ_k sums to the difference; its long-run variance is the difference's.
  const Vector6 g = (g_meas - g_pred).cwiseProduct(c.free);
  const double fitted = g.dot(*c.covariance * g);
  const Vector6 v_psi_h = *c.influence_map * s.v_gh;
  double variance = s.v_hh + 2.0 * g.dot(v_psi_h) + g.dot(c.influence_long_run * g);
  variance = std::max(variance, 0.01 * (s.v_hh + fitted));  // Never below a tenth of the σ sum.
  total.sigma_measured = std::sqrt(std::max(s.v_hh, 0.0));
  total.sigma_predicted = std::sqrt(std::max(g_pred.dot(*c.covariance * g_pred), 0.0));
  total.sigma_ends = std::sqrt(s.ends);
  total.sigma = std::sqrt(variance + s.ends);
  const double d = total.measured - total.predicted;
  total.z = total.sigma > 0.0 ? d / total.sigma : 0.0;
  total.p_value = std::erfc(std::abs(total.z) / std::sqrt(2.0));
  return total;
}

// What CheckWindow sums over a window, chunk by chunk.
struct WindowSums {
  int intervals = 0;
  Eigen::Vector3d travel_gradient = Eigen::Vector3d::Zero();
  QuantitySums rotation_sums, travel_sums;
  WindowSums& operator+=(const WindowSums& o) {
    intervals += o.intervals;
    travel_gradient += o.travel_gradient;
    rotation_sums += o.rotation_sums;
    travel_sums += o.travel_sums;
    return *this;
  }
};

LaserConsistencyWindow CheckWindow(const Context& rotation_context, const Context& travel_context,
                                   const LogTerms& log, const Window& w,
                                   const LaserCalibration& estimate) {
  const OdometryParams& odo = estimate.odometry;
  LaserConsistencyWindow out;
  out.log = w.log;
  out.kind = w.kind;
  out.first = w.first;
  out.last = w.last;
  const std::vector<LaserInterval>& in = *log.intervals;
  out.start_s = in[w.first].start_s;
  out.end_s = in[w.last].start_s + in[w.last].duration_s;
  const auto rotation_difference = [](const IntervalTerms& t) { return t.rotation_difference(); };
  const auto rotation_predicted = [](const IntervalTerms& t) { return t.rotation_predicted; };
  const auto travel_difference = [](const IntervalTerms& t) { return t.travel_difference(); };
  const auto travel_predicted = [](const IntervalTerms& t) { return t.travel_predicted; };
  const size_t length = static_cast<size_t>(w.last - w.first + 1);
  std::vector<WindowSums> chunks(SplitCount(length, kMinChunkIntervals));
  ParallelSplit(length, rotation_context.options->num_threads, kMinChunkIntervals,
                [&](size_t chunk, size_t begin, size_t end) {
                  WindowSums& s = chunks[chunk];
                  const long first = w.first + static_cast<long>(begin);
                  const long last = w.first + static_cast<long>(end);
                  QuantityPass rotation(rotation_context, log, w, first, rotation_difference,
                                        rotation_predicted);
                  QuantityPass travel(travel_context, log, w, first, travel_difference,
                                      travel_predicted);
                  for (long k = first; k < last; ++k) {
                    rotation.Step(k);
                    travel.Step(k);
                    const IntervalTerms& t = log.terms[k];
                    if (!t.counted) continue;
                    ++s.intervals;
                    s.travel_gradient += t.travel_gradient.cast<double>();
                  }
                  s.rotation_sums = rotation.sums();
                  s.travel_sums = travel.sums();
                });
  WindowSums sums;
  for (const WindowSums& s : chunks) sums += s;
  // The cut after the window's last interval.
  sums.rotation_sums.ends +=
      CutVariance(*rotation_context.options, log, w, w.last + 1, rotation_predicted);
  sums.travel_sums.ends +=
      CutVariance(*travel_context.options, log, w, w.last + 1, travel_predicted);
  out.intervals = sums.intervals;
  // Each wheel's rotation summed over the counted intervals, from the predicted totals R and T
  // (linear in it): r_l·φ_l = T − R·b/2, r_r·φ_r = T + R·b/2.
  const double rotation = sums.rotation_sums.predicted;
  const double half_turn = rotation * odo.wheelbase_m / 2.0;
  const Eigen::Vector2d wheel((sums.travel_sums.predicted - half_turn) / odo.left_radius_m,
                              (sums.travel_sums.predicted + half_turn) / odo.right_radius_m);
  // Gradients of the totals in (r_l, r_r, b, x, y, θ).
  Vector6 g_rotation, g_travel, g_travel_measured;
  g_rotation << -wheel(0) / odo.wheelbase_m, wheel(1) / odo.wheelbase_m,
      -rotation / odo.wheelbase_m, 0.0, 0.0, 0.0;
  g_travel << wheel(0) / 2.0, wheel(1) / 2.0, 0.0, 0.0, 0.0, 0.0;
  g_travel_measured << 0.0, 0.0, 0.0, sums.travel_gradient;
  out.rotation = Total(rotation_context, sums.rotation_sums, g_rotation, Vector6::Zero());
  out.translation = Total(travel_context, sums.travel_sums, g_travel, g_travel_measured);
  return out;
}

std::string Warning(const LaserConsistencyWindow& w, bool rotation, bool several_logs) {
  const LaserConsistencyTotal& t = rotation ? w.rotation : w.translation;
  const double k = rotation ? 180.0 / M_PI : 1.0;
  const char* f = rotation ? "%.1f° ± %.1f°" : "%.3f m ± %.3f m";
  std::string text = several_logs ? Format("log %d: ", w.log + 1) : std::string();
  text += "the wheel model predicts " + Format(f, t.predicted * k, t.sigma_predicted * k) +
          (rotation ? " of rotation" : " of travel") +
          Format(" over t = %.1f–%.1f s (%s, intervals %d–%d, %d inliers)", w.start_s, w.end_s,
                 w.kind.c_str(), w.first + 1, w.last + 1, w.intervals) +
          " where the sensor measured " + Format(f, t.measured * k, t.sigma_measured * k) +
          Format(" (difference %.1fσ, σ ", t.z) +
          Format(rotation ? "%.1f°" : "%.3f m", t.sigma * k) +
          "): these totals do not depend on the timing of the samples, so the calibration is "
          "likely biased; causes: the stamps may not be the sample times (timing), the wheels may "
          "slip, or the wheel rotation may be in the wrong units";
  return text;
}

// Holm over every test; warnings for the most significant rejected ones.
void Decide(const LaserConsistencyOptions& options, bool several_logs, LaserConsistency* out) {
  std::vector<double> p_values;
  for (const LaserConsistencyWindow& w : out->windows) {
    p_values.push_back(w.rotation.p_value);
    p_values.push_back(w.translation.p_value);
  }
  out->tests = static_cast<int>(p_values.size());
  std::vector<std::pair<double, std::string>> flagged;
  for (const HolmStep& step : Holm(p_values, options.family_alpha)) {
    if (!step.rejected) continue;
    LaserConsistencyWindow& w = out->windows[step.index / 2];
    const bool rotation = step.index % 2 == 0;
    (rotation ? w.rotation : w.translation).significant = true;
    flagged.emplace_back(step.p_value, Warning(w, rotation, several_logs));
  }
  for (size_t i = 0; i < flagged.size(); ++i) {
    if (static_cast<int>(i) == options.max_warnings) {
      out->warnings.push_back(Format("%d more windows disagree the same way (see the JSON)",
                                     static_cast<int>(flagged.size() - i)));
      break;
    }
    out->warnings.push_back(flagged[i].second);
  }
}

}  // namespace

LaserConsistency CheckLaserConsistencyJoint(
    const std::vector<const std::vector<LaserInterval>*>& logs, const LaserCalibration& estimate,
    const LaserParamMatrix& covariance, const std::vector<Eigen::Vector3d>& noise_sigma,
    const std::vector<std::vector<bool>>& is_inlier, const LaserConsistencyOptions& options) {
  LaserConsistency out;
  if (logs.empty() || noise_sigma.size() != logs.size() ||
      (!is_inlier.empty() && is_inlier.size() != logs.size())) {
    out.note = "not checked: one noise level and one inlier vector per log are needed";
    return out;
  }
  for (size_t d = 0; d < is_inlier.size(); ++d) {
    if (is_inlier[d].size() != logs[d]->size()) {
      out.note = "not checked: the inlier flags do not match the intervals";
      return out;
    }
  }
  Context c;
  c.options = &options;
  c.covariance = &covariance;
  for (int i = 0; i < kNumLaserParams; ++i) {
    c.free(i) = covariance(i, i) > 0.0 && std::isfinite(covariance(i, i)) ? 1.0 : 0.0;
  }
  if (c.free.sum() == 0.0 || !covariance.allFinite()) {
    out.note = "not checked: the calibration has no covariance";
    return out;
  }
  LaserParamMatrix hessian = LaserParamMatrix::Zero();
  std::vector<LogTerms> terms;
  for (size_t d = 0; d < logs.size(); ++d) {
    static const std::vector<bool> kAll;
    terms.push_back(ComputeTerms(*logs[d], estimate, noise_sigma[d],
                                 is_inlier.empty() ? kAll : is_inlier[d], &hessian,
                                 options.num_threads));
  }
  // Parameters held fixed do not move with the data: their rows of H become the identity.
  for (int i = 0; i < kNumLaserParams; ++i) {
    if (c.free(i) > 0.0) continue;
    hessian.row(i).setZero();
    hessian.col(i).setZero();
    hessian(i, i) = 1.0;
  }
  const Eigen::LDLT<LaserParamMatrix> ldlt(hessian);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
    out.note = "not checked: the inliers do not determine the parameters";
    return out;
  }
  // ψ_k = A·g_k with A = −H⁻¹ on the free parameters: θ̂ − θ ≈ Σψ_k.
  const LaserParamMatrix influence_map = -ldlt.solve(LaserParamMatrix(c.free.asDiagonal()));
  c.influence_map = &influence_map;
  // Each quantity with its own lag (Andrews) and the estimate's long-run covariance at it.
  Context rotation = c, travel = c;
  const std::array<int, 2> lags = AutomaticLags(terms, options.num_threads);
  rotation.lag = lags[0];
  travel.lag = lags[1];
  const std::vector<LaserParamMatrix> score_long_run =
      ScoreLongRun(terms, {rotation.lag, travel.lag}, options.num_threads);
  rotation.influence_long_run = influence_map * score_long_run[0] * influence_map.transpose();
  travel.influence_long_run = influence_map * score_long_run[1] * influence_map.transpose();
  out.rotation_lag = rotation.lag;
  out.translation_lag = travel.lag;
  const std::vector<Window> windows = FindWindows(terms, options.min_window_intervals);
  out.windows.resize(windows.size());
  // A long window splits its sums across the threads; the short ones (a long log has a thousand
  // stretches between rests) go side by side instead, each on one thread. The chunks and their
  // order are the same either way (ParallelSplit), and so are the sums.
  std::vector<size_t> short_windows;
  for (size_t i = 0; i < windows.size(); ++i) {
    const Window& w = windows[i];
    if (SplitCount(static_cast<size_t>(w.last - w.first + 1), kMinChunkIntervals) > 1) {
      out.windows[i] = CheckWindow(rotation, travel, terms[w.log], w, estimate);
    } else {
      short_windows.push_back(i);
    }
  }
  ParallelSplit(
      short_windows.size(), options.num_threads, 1, [&](size_t, size_t begin, size_t end) {
        for (size_t j = begin; j < end; ++j) {
          const Window& w = windows[short_windows[j]];
          out.windows[short_windows[j]] = CheckWindow(rotation, travel, terms[w.log], w, estimate);
        }
      });
  if (out.windows.empty()) {
    out.note =
        Format("not checked: no run holds %d inlier intervals", options.min_window_intervals);
    return out;
  }
  out.checked = true;
  Decide(options, logs.size() > 1, &out);
  return out;
}

LaserConsistency CheckLaserConsistency(const std::vector<LaserInterval>& intervals,
                                       const LaserCalibration& estimate,
                                       const LaserParamMatrix& covariance,
                                       const Eigen::Vector3d& noise_sigma,
                                       const std::vector<bool>& is_inlier,
                                       const LaserConsistencyOptions& options) {
  return CheckLaserConsistencyJoint({&intervals}, estimate, covariance, {noise_sigma},
                                    is_inlier.empty() ? std::vector<std::vector<bool>>{}
                                                      : std::vector<std::vector<bool>>{is_inlier},
                                    options);
}

}  // namespace calib
