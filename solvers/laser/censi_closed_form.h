#ifndef CALIB_SOLVERS_LASER_CENSI_CLOSED_FORM_H_
#define CALIB_SOLVERS_LASER_CENSI_CLOSED_FORM_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/status.h>

#include <vector>

// The closed-form estimator of Censi, Marchionni, Oriolo (ICRA 2008), §II-B, C, D, E.
namespace calib {

struct CensiClosedFormOptions {
  // Above this condition number the linear systems are treated as degenerate.
  double max_condition_number = 1e7;
  // On long logs the sums over the intervals run in this many chunks at once.
  int num_threads = 2;
};

struct CensiClosedFormResult {
  LaserCalibration calibration;
  double j21 = 0.0;                 // −r_l/b
  double j22 = 0.0;                 // +r_r/b
  double j_condition_number = 0.0;  // Of the stacked [Δφ_l Δφ_r] system (eq. 8).
  double lambda = 0.0;              // Lagrange multiplier of the constraint x4² + x5² = 1.
  int samples_used = 0;
};

// Estimates all six parameters from the intervals with use[k] true (all when `use` is null).
// Returns an error naming the missing motion on degenerate data; never exits. Swapped or
// sign-reversed wheels and wrong units are named by CheckLaserInput (laser_input_checks.h).
StatusOr<CensiClosedFormResult> CensiClosedForm(const std::vector<LaserInterval>& intervals,
                                                const std::vector<bool>* use = nullptr,
                                                const CensiClosedFormOptions& options = {});

// The paper's §III-B outlier handling, kept as a baseline: estimate, drop the worst `fraction`
// of the samples by the residual e = ℓ ⊕ ŝ − ô ⊕ ℓ (separately on |e_xy| and |e_θ|), repeat
// `rounds` times (the paper: 5 % three times).
// Before the first round, gross records are left out by a consensus (censi_consensus.h) unless
// `screen_gross` is false (the paper's own procedure), so that one glitch costs one interval.
struct TrimmedClosedFormOptions {
  int rounds = 3;
  double fraction = 0.05;
  bool screen_gross = true;
  CensiClosedFormOptions closed_form;
};
struct TrimmedClosedFormResult {
  CensiClosedFormResult estimate;
  std::vector<bool> kept;
  int gross = 0;  // Intervals the consensus screen left out before the rounds.
  int first_gross = -1;
};
// `screen`, when not null, is these intervals' consensus screen under options.closed_form,
// already computed (ScreenGrossIntervals): it is used instead of screening again.
struct ConsensusScreen;
StatusOr<TrimmedClosedFormResult> CensiClosedFormTrimmed(
    const std::vector<LaserInterval>& intervals, const TrimmedClosedFormOptions& options = {},
    const ConsensusScreen* screen = nullptr);

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_CENSI_CLOSED_FORM_H_
