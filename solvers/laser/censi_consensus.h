#ifndef CALIB_SOLVERS_LASER_CENSI_CONSENSUS_H_
#define CALIB_SOLVERS_LASER_CENSI_CONSENSUS_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/status.h>
#include <calib/solvers/laser/censi_closed_form.h>

#include <optional>
#include <vector>

// Gross records found before any least squares sees them. One wheel speed of 1000 rad/s, one T
// of 10⁴ s or one rotation of π written as −π is a lever on the closed form's sums: it drags
// the plain (and the trimmed, which ranks residuals of the dragged fit) estimate to negative or
// zero radii. A consensus cannot be dragged: each stage of the closed form is fitted to many
// small random subsets (least median of squares, Rousseeuw 1984), and the fit that the median
// interval agrees with best decides which intervals are gross.
//   1. rotation: ŝ_θ = [Δφ_l Δφ_r]·[J21 J22]ᵀ from pairs of intervals;
//   2. translation: eq. 16 from four intervals, with J from the rotation stage's inliers.
// An interval whose residual exceeds `cut` robust sigmas (1.4826 × the median absolute
// residual) of its stage is gross. Deterministic (a fixed seed).
namespace calib {

struct ConsensusScreenOptions {
  int trials = 300;      // Random subsets per stage.
  int evaluated = 2000;  // Intervals (evenly spread) each trial is scored on.
  double cut = 8.0;      // Robust sigmas beyond which an interval is gross.
  CensiClosedFormOptions closed_form;
};

struct ConsensusScreen {
  std::vector<bool> kept;  // False for a gross interval.
  int rotation_outliers = 0;
  int translation_outliers = 0;
  int first_outlier = -1;  // Index of the first gross interval, −1 when none.
  // The closed form on the kept intervals under the default options, when CensiClosedFormScreened
  // computed it and it succeeded (ClosedFormOnKept reuses it).
  std::optional<CensiClosedFormResult> closed_form;
  int outliers() const { return rotation_outliers + translation_outliers; }
};

// Never fails: a log too small or too degenerate for a consensus keeps every interval.
ConsensusScreen ScreenGrossIntervals(const std::vector<LaserInterval>& intervals,
                                     const ConsensusScreenOptions& options = {});

// The closed form on the intervals the screen keeps (`screen` may be null).
StatusOr<CensiClosedFormResult> CensiClosedFormScreened(const std::vector<LaserInterval>& intervals,
                                                        ConsensusScreen* screen = nullptr);

// The closed form on the intervals `screen` keeps: the screen's own (screen.closed_form) under the
// default options, else computed.
StatusOr<CensiClosedFormResult> ClosedFormOnKept(const std::vector<LaserInterval>& intervals,
                                                 const ConsensusScreen& screen,
                                                 const CensiClosedFormOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_CENSI_CONSENSUS_H_
