#include <calib/core/order_statistic.h>
#include <calib/core/random.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/laser/censi_closed_form_internal.h>
#include <calib/solvers/laser/censi_consensus.h>
#include <calib/solvers/laser/laser_motion.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>

namespace calib {
namespace {

using censi_internal::Matrix5d;
using censi_internal::TranslationRows;
using censi_internal::Vector5d;

constexpr double kStillRad = 1e-6;  // Wheels at rest: no say in the rotation consensus.
constexpr double kMadToSigma = 1.4826;
constexpr uint64_t kSeed = 20080519;  // Fixed: the same log gives the same screen.

double Median(std::vector<double> v) { return UpperMedian(&v); }

// Whether Median of value(0 … n−1) is below `bound`, i.e. at least n/2 + 1 values are: a count
// that stops as soon as it is decided, where most candidates of a consensus search lose (the
// same answer as Median(…) < bound without the selection, but for the sequential test). A loser
// is only known for sure after about n/2 values, so the values come in SpreadOrder (each prefix
// an evenly spread sample of the log) and a candidate with fewer than half of those counted so
// far below, by 4 binomial σ, is dropped (a winner is, with a chance below 10⁻⁴ at each of the
// few checks; the search then keeps a slightly worse candidate). The count runs in blocks, each
// a tight loop the compiler vectorizes, and decides between blocks.
template <typename F>
bool MedianBelow(size_t n, double bound, const F& value) {
  constexpr size_t kBlock = 128;
  const size_t needed = n / 2 + 1;
  size_t below = 0;
  for (size_t start = 0; start < n; start += kBlock) {
    const size_t end = std::min(n, start + kBlock);
    for (size_t i = start; i < end; ++i) below += value(i) < bound;
    if (below >= needed) return true;
    if (below + (n - end) < needed) return false;
    const double counted = static_cast<double>(end);
    if (static_cast<double>(below) < 0.5 * counted - 2.0 * std::sqrt(counted)) return false;
  }
  return false;
}

// 0 … n−1 in bit-reversed order (of the next power of two, skipping what is ≥ n): every prefix
// spreads evenly over them, so that a count over a prefix samples the whole log.
std::vector<size_t> SpreadOrder(size_t n) {
  int bits = 0;
  while ((size_t{1} << bits) < n) ++bits;
  std::vector<size_t> order;
  order.reserve(n);
  for (size_t p = 0; p < (size_t{1} << bits); ++p) {
    size_t reversed = 0;
    for (int b = 0; b < bits; ++b) reversed |= ((p >> b) & 1) << (bits - 1 - b);
    if (reversed < n) order.push_back(reversed);
  }
  return order;
}

// pred(k) for k in [0, n), in parallel chunks (pred only reads).
constexpr size_t kMinChunk = 500;
template <typename F>
std::vector<char> Flags(size_t n, int threads, const F& pred) {
  std::vector<char> flags(n);
  ParallelSplit(n, threads, kMinChunk, [&](size_t, size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) flags[k] = pred(k);
  });
  return flags;
}

// Up to `count` indices evenly spread over `from`.
std::vector<size_t> Spread(const std::vector<size_t>& from, int count) {
  if (from.size() <= static_cast<size_t>(count)) return from;
  std::vector<size_t> out;
  for (int i = 0; i < count; ++i) out.push_back(from[from.size() * i / count]);
  return out;
}

// The consensus search over `trials` drawn subsets: candidate(t) fits the t-th, and a candidate
// whose median misfit is below the best one's so far (MedianBelow) becomes the best, with
// score(candidate). The trials run in two fixed halves side by side (while the checks run, the
// screen's thread waits and its core is free), each from the given best; the second half's best
// replaces the first's only when its score is lower. That is the sequential search's choice (the
// lowest score, the earlier on a tie), up to MedianBelow's rare drops, whatever the threads.
template <typename T, typename Candidate, typename Below, typename Score>
void BestOfTrials(int trials, int threads, const Candidate& candidate, const Below& below,
                  const Score& score, std::optional<T>* best, double* best_score) {
  constexpr int kHalves = 2;
  std::optional<T> found[kHalves];
  double found_score[kHalves] = {*best_score, *best_score};
  const size_t min_chunk = std::max<size_t>(1, (static_cast<size_t>(trials) + 1) / kHalves);
  ParallelSplit(static_cast<size_t>(trials), threads, min_chunk,
                [&](size_t half, size_t begin, size_t end) {
                  for (size_t t = begin; t < end; ++t) {
                    const std::optional<T> x = candidate(t);
                    if (!x || !below(*x, found_score[half])) continue;
                    found_score[half] = score(*x);
                    found[half] = x;
                  }
                });
  for (int half = 0; half < kHalves; ++half) {
    if (found[half] && found_score[half] < *best_score) {
      *best = found[half];
      *best_score = found_score[half];
    }
  }
}

double RotationResidual(const LaserInterval& interval, const Eigen::Vector2d& j) {
  return interval.sensor_motion(2) - IntervalWheelRotation(interval).dot(j);
}

// The scored intervals' rotation equations, one array per term: |θ_k − a_kᵀJ| in a tight loop.
struct RotationColumns {
  explicit RotationColumns(const std::vector<LaserInterval>& intervals,
                           const std::vector<size_t>& which) {
    for (size_t i : SpreadOrder(which.size())) {  // For MedianBelow.
      const size_t k = which[i];
      const Eigen::Vector2d a = IntervalWheelRotation(intervals[k]);
      left.push_back(a(0)), right.push_back(a(1)), theta.push_back(intervals[k].sensor_motion(2));
    }
  }
  double Residual(size_t i, const Eigen::Vector2d& j) const {
    return std::abs(theta[i] - (left[i] * j(0) + right[i] * j(1)));
  }
  std::vector<double> left, right, theta;
};

// J by least squares over `indices`, or nothing when they do not determine it.
std::optional<Eigen::Vector2d> FitRotation(const std::vector<LaserInterval>& intervals,
                                           const std::vector<size_t>& indices) {
  Eigen::Matrix2d ata = Eigen::Matrix2d::Zero();
  Eigen::Vector2d atb = Eigen::Vector2d::Zero();
  for (size_t k : indices) {
    const Eigen::Vector2d a = IntervalWheelRotation(intervals[k]);
    ata += a * a.transpose();
    atb += a * intervals[k].sensor_motion(2);
  }
  // Scaled, the 2×2 system is singular when the wheel-speed ratios are (nearly) all the same.
  const Eigen::Vector2d d = ata.diagonal();
  if (!(d.minCoeff() > 0.0) || !(ata.determinant() > 1e-8 * d(0) * d(1))) return std::nullopt;
  const Eigen::Vector2d j = ata.ldlt().solve(atb);
  if (!j.allFinite()) return std::nullopt;
  return j;
}

// Stage 1: the J that the median moving interval agrees with best, and the gross intervals.
std::optional<Eigen::Vector2d> RotationConsensus(const std::vector<LaserInterval>& intervals,
                                                 const std::vector<size_t>& moving,
                                                 const ConsensusScreenOptions& options,
                                                 ConsensusScreen* screen) {
  const RotationColumns scored(intervals, Spread(moving, options.evaluated));
  const size_t n = scored.theta.size();
  const auto score = [&](const Eigen::Vector2d& j) {
    std::vector<double> r(n);
    for (size_t i = 0; i < n; ++i) r[i] = scored.Residual(i, j);
    return Median(std::move(r));
  };
  std::optional<Eigen::Vector2d> best = FitRotation(intervals, moving);
  double best_score = best ? score(*best) : std::numeric_limits<double>::infinity();
  // The pairs drawn in turn up front: the same pairs however the trials are run.
  Random random(kSeed, 1);
  std::vector<std::vector<size_t>> pairs(std::max(options.trials, 0));
  for (std::vector<size_t>& pair : pairs) {
    pair = {moving[random.Index(moving.size())], moving[random.Index(moving.size())]};
  }
  BestOfTrials<Eigen::Vector2d>(
      options.trials, options.closed_form.num_threads,
      [&](size_t t) { return FitRotation(intervals, pairs[t]); },
      [&](const Eigen::Vector2d& j, double bound) {
        return MedianBelow(n, bound, [&](size_t i) { return scored.Residual(i, j); });
      },
      score, &best, &best_score);
  if (!best) return std::nullopt;
  const double cut = options.cut * kMadToSigma * best_score + 1e-12;
  const std::vector<char> gross =
      Flags(intervals.size(), options.closed_form.num_threads,
            [&](size_t k) { return std::abs(RotationResidual(intervals[k], *best)) > cut; });
  for (size_t k = 0; k < intervals.size(); ++k) {
    if (gross[k]) {
      screen->kept[k] = false;
      ++screen->rotation_outliers;
    }
  }
  return best;
}

std::optional<Vector5d> SolveRows(const std::vector<TranslationRows>& rows,
                                  const std::vector<size_t>& which,
                                  const ConsensusScreenOptions& options) {
  Matrix5d m = Matrix5d::Zero();
  for (size_t i : which) m += rows[i].transpose() * rows[i];
  const StatusOr<Vector5d> x = censi_internal::SolveTranslation(m, options.closed_form, nullptr);
  if (!x.ok()) return std::nullopt;
  return *x;
}

// Eq. 16's rows, one array per entry (in SpreadOrder): |L_k x| in a tight loop.
struct TranslationColumns {
  explicit TranslationColumns(const std::vector<TranslationRows>& rows) {
    for (int e = 0; e < 10; ++e) entry[e].resize(rows.size());
    const std::vector<size_t> order = SpreadOrder(rows.size());  // For MedianBelow.
    for (size_t i = 0; i < rows.size(); ++i) {
      for (int e = 0; e < 10; ++e) entry[e][i] = rows[order[i]](e / 5, e % 5);
    }
  }
  // |L_i x|², compared squared: no square root per interval and trial.
  double SquaredMisfit(size_t i, const Vector5d& x) const {
    double u = 0.0, v = 0.0;
    for (int c = 0; c < 5; ++c) u += entry[c][i] * x(c), v += entry[5 + c][i] * x(c);
    return u * u + v * v;
  }
  std::vector<double> entry[10];
};

// Stage 2: eq. 16's x that the median kept interval agrees with best, and the gross intervals.
void TranslationConsensus(const std::vector<LaserInterval>& intervals, const Eigen::Vector2d& j,
                          const ConsensusScreenOptions& options, ConsensusScreen* screen) {
  std::vector<size_t> kept_moving;
  for (size_t k = 0; k < intervals.size(); ++k) {
    if (screen->kept[k] && IntervalWheelRotation(intervals[k]).cwiseAbs().sum() >= kStillRad) {
      kept_moving.push_back(k);
    }
  }
  const std::vector<size_t> scored = Spread(kept_moving, options.evaluated);
  if (scored.size() < 4) return;
  std::vector<TranslationRows> rows;
  for (size_t k : scored)
    rows.push_back(censi_internal::TranslationEquations(intervals[k], j(0), j(1)));
  const TranslationColumns columns(rows);
  // The median squared misfit (the square of the median misfit: the square root is monotone).
  const auto score = [&](const Vector5d& x) {
    std::vector<double> e(rows.size());
    for (size_t i = 0; i < rows.size(); ++i) e[i] = columns.SquaredMisfit(i, x);
    return Median(std::move(e));
  };
  std::vector<size_t> all(rows.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  std::optional<Vector5d> best = SolveRows(rows, all, options);
  double best_score = best ? score(*best) : std::numeric_limits<double>::infinity();
  Random random(kSeed, 2);
  std::vector<std::vector<size_t>> subsets(std::max(options.trials, 0), std::vector<size_t>(4));
  for (std::vector<size_t>& subset : subsets) {
    for (size_t& i : subset) i = random.Index(rows.size());
  }
  BestOfTrials<Vector5d>(
      options.trials, options.closed_form.num_threads,
      [&](size_t t) { return SolveRows(rows, subsets[t], options); },
      [&](const Vector5d& x, double bound) {
        return MedianBelow(rows.size(), bound,
                           [&](size_t i) { return columns.SquaredMisfit(i, x); });
      },
      score, &best, &best_score);
  if (!best) return;
  const double cut = options.cut * kMadToSigma * std::sqrt(best_score) + 1e-12;
  const std::vector<char> gross =
      Flags(intervals.size(), options.closed_form.num_threads, [&](size_t k) {
        if (!screen->kept[k]) return false;
        const TranslationRows l = censi_internal::TranslationEquations(intervals[k], j(0), j(1));
        return !((l * *best).norm() <= cut);
      });
  for (size_t k = 0; k < intervals.size(); ++k) {
    if (gross[k]) {
      screen->kept[k] = false;
      ++screen->translation_outliers;
    }
  }
}

}  // namespace

ConsensusScreen ScreenGrossIntervals(const std::vector<LaserInterval>& intervals,
                                     const ConsensusScreenOptions& options) {
  ConsensusScreen screen;
  screen.kept.assign(intervals.size(), true);
  std::vector<size_t> moving;
  for (size_t k = 0; k < intervals.size(); ++k) {
    if (IntervalWheelRotation(intervals[k]).cwiseAbs().sum() >= kStillRad) moving.push_back(k);
  }
  if (moving.size() < 4) return screen;
  const std::optional<Eigen::Vector2d> rotation =
      RotationConsensus(intervals, moving, options, &screen);
  if (!rotation) return screen;
  // J again by least squares, now over the rotation stage's inliers only.
  std::vector<size_t> inliers;
  for (size_t k : moving) {
    if (screen.kept[k]) inliers.push_back(k);
  }
  const std::optional<Eigen::Vector2d> j = FitRotation(intervals, inliers);
  if (j) TranslationConsensus(intervals, *j, options, &screen);
  const auto first = std::find(screen.kept.begin(), screen.kept.end(), false);
  if (first != screen.kept.end())
    screen.first_outlier = static_cast<int>(first - screen.kept.begin());
  return screen;
}

StatusOr<CensiClosedFormResult> CensiClosedFormScreened(const std::vector<LaserInterval>& intervals,
                                                        ConsensusScreen* screen) {
  ConsensusScreen local = ScreenGrossIntervals(intervals);
  const StatusOr<CensiClosedFormResult> result = CensiClosedForm(intervals, &local.kept);
  if (result.ok()) local.closed_form = *result;
  if (screen != nullptr) *screen = std::move(local);
  return result;
}

StatusOr<CensiClosedFormResult> ClosedFormOnKept(const std::vector<LaserInterval>& intervals,
                                                 const ConsensusScreen& screen,
                                                 const CensiClosedFormOptions& options) {
  const CensiClosedFormOptions defaults;
  if (screen.closed_form && screen.kept.size() == intervals.size() &&
      options.max_condition_number == defaults.max_condition_number &&
      options.num_threads == defaults.num_threads) {
    return *screen.closed_form;
  }
  return CensiClosedForm(intervals, &screen.kept, options);
}

}  // namespace calib
