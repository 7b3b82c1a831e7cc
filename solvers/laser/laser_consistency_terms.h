#ifndef CALIB_SOLVERS_LASER_LASER_CONSISTENCY_TERMS_H_
#define CALIB_SOLVERS_LASER_LASER_CONSISTENCY_TERMS_H_

#include <calib/core/default_init_allocator.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

// The per-interval pieces of the consistency check (laser_consistency.h) and the long-run
// variances it sums them with. Internal to the check; exposed for its tests.
namespace calib {
struct SensorMounting;  // problems/laser/laser_residual.h
}  // namespace calib

namespace calib::consistency_internal {

using Vector6 = Eigen::Matrix<double, kNumLaserParams, 1>;

// The check's passes run in chunks of at least this many intervals (ParallelSplit).
constexpr size_t kMinChunkIntervals = 500;

// The robot's forward travel over an interval from the sensor displacement: o = ℓ ∘ sm ∘ ℓ⁻¹,
// and the component of its chord along the mid-interval heading over sinc(Δθ/2). For an arc of
// length d turning by Δθ this is d exactly (the chord is d·sinc(Δθ/2) along the mid heading); on
// noisy near-still intervals it stays linear in the noise, where a signed |chord| would rectify
// it. Also gives ∂travel/∂ℓ.
double ForwardTravel(const Pose2d& sensor_motion, const Pose2d& base_T_sensor,
                     Eigen::Vector3d* gradient = nullptr);
// The same with the mounting's sine and cosine computed once for all intervals.
double ForwardTravel(const Pose2d& sensor_motion, const SensorMounting& mounting,
                     Eigen::Vector3d* gradient);

// What each interval adds to the totals and to the fit. A million intervals hold one each: what
// the interval itself gives (its T, its wheel rotation) is read from it, and the vectors that are
// only summed (over windows, lags and the log) are kept in single precision: 72 bytes instead of
// 136, and the sums, in double, move by ~1e-11 relative. No initial values: ComputeTerms writes
// every field, and a million of them are allocated without writing them first (TermsVector).
struct IntervalTerms {
  bool counted;  // Enters the sums: an inlier, or an outlier rescued as a timing artefact.
  bool still;    // The robot rests (wheel model and noise agree on no motion).
  Eigen::Vector3f travel_gradient;  // ∂travel_measured/∂ℓ.
  double rotation_predicted, rotation_measured;
  double travel_predicted, travel_measured;
  // The score g = JᵀWe of the fit's inliers (0 otherwise). The interval's share of θ̂ − θ is its
  // influence ψ = A·g, A = −H⁻¹ (free parameters only); every sum of ψ is linear in g, so the
  // check sums the scores and applies A once.
  Eigen::Matrix<float, kNumLaserParams, 1> score;
  Vector6 Score() const { return score.cast<double>(); }
  double rotation_difference() const { return rotation_measured - rotation_predicted; }
  double travel_difference() const { return travel_measured - travel_predicted; }
};
using TermsVector = std::vector<IntervalTerms, DefaultInitAllocator<IntervalTerms>>;

struct LogTerms {
  const std::vector<LaserInterval>* intervals = nullptr;
  TermsVector terms;
};

// Every term of a log at the estimate; adds the fit's JᵀWJ (its inliers, W = diag(1/σ²)) to
// `hessian`. An outlier of the fit is counted all the same when its differences summed with a
// neighbour's agree within 4σ√2 in rotation and travel: its wheel rotation belongs partly to the
// neighbour (a misplaced stamp), the sensor did not fail; dropping it would leave the shifted
// rotation of its boundaries in the totals.
LogTerms ComputeTerms(const std::vector<LaserInterval>& intervals, const LaserCalibration& c,
                      const Eigen::Vector3d& noise_sigma, const std::vector<bool>& is_inlier,
                      LaserParamMatrix* hessian, int num_threads = 1);

// Bartlett-weighted sums of a sequence x_i (0 outside the range `x` gives) at k = k0, k0 + 1, …:
//   Centred: Σ_{|j|≤L} (1 − |j|/(L+1))·x_{k+j},   Ahead: Σ_{j=1..L} (1 − j/(L+1))·x_{k+j}.
// A triangle is a running sum of running boxes: O(1) a step instead of O(L) (a window of a million
// intervals at L ≈ 20). Unnormalised sums: T = Σ(L+1−|j|)x_{k+j}, R = Σ_{k+1}^{k+L+1} x,
// B = Σ_{k−L}^{k} x; T_{k+1} = T_k + R_k − B_k. Ahead: U = Σ_{m=1..L}(L+1−m)x_{k+m},
// S = Σ_{m=2..L+1} x_{k+m}; U_{k+1} = U_k − L·x_{k+1} + S_k.
template <typename Value, typename X>
class BartlettCentred {
 public:
  BartlettCentred(X x, int lag, long k0) : x_(x), lag_(lag), k_(k0) {
    t_ = r_ = b_ = x_(k0) * 0.0;
    for (long j = -lag; j <= lag; ++j) t_ += (lag + 1.0 - std::abs(j)) * x_(k0 + j);
    for (long i = k0 + 1; i <= k0 + lag + 1; ++i) r_ += x_(i);
    for (long i = k0 - lag; i <= k0; ++i) b_ += x_(i);
  }
  Value value() const { return t_ / (lag_ + 1.0); }
  void Advance() {
    t_ += r_ - b_;
    r_ += x_(k_ + lag_ + 2) - x_(k_ + 1);
    b_ += x_(k_ + 1) - x_(k_ - lag_);
    ++k_;
  }

 private:
  X x_;
  int lag_;
  long k_;
  Value t_, r_, b_;
};

template <typename Value, typename X>
class BartlettAhead {
 public:
  BartlettAhead(X x, int lag, long k0) : x_(x), lag_(lag), k_(k0) {
    u_ = s_ = x_(k0) * 0.0;
    for (long m = 1; m <= lag; ++m) u_ += (lag + 1.0 - m) * x_(k0 + m);
    for (long m = 2; m <= lag + 1; ++m) s_ += x_(k0 + m);
  }
  Value value() const { return u_ / (lag_ + 1.0); }
  void Advance() {
    u_ += s_ - lag_ * x_(k_ + 1);
    s_ += x_(k_ + lag_ + 2) - x_(k_ + 2);
    ++k_;
  }

 private:
  X x_;
  int lag_;
  long k_;
  Value u_, s_;
};

// Andrews (1991) automatic Bartlett lags from AR(1) fits to the counted rotation and travel
// differences of every log (in that order), in one pass: 1.1447·(α·n)^{1/3},
// α = 4ρ²/((1 − ρ)²(1 + ρ)²); at least 1, at most n/4. Negative correlation (telescoping poses,
// misplaced stamps) and positive (model errors) both lengthen it.
std::array<int, 2> AutomaticLags(const std::vector<LogTerms>& logs, int num_threads = 1);

// The long-run (HAC) covariance of Σg_k over every log at each of `lags`, in one pass; with A
// (IntervalTerms::score) it gives the estimate's sandwich with its serial correlation, A·S·Aᵀ.
std::vector<LaserParamMatrix> ScoreLongRun(const std::vector<LogTerms>& logs,
                                           const std::vector<int>& lags, int num_threads = 1);

}  // namespace calib::consistency_internal

#endif  // CALIB_SOLVERS_LASER_LASER_CONSISTENCY_TERMS_H_
