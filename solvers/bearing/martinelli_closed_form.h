#ifndef CALIB_SOLVERS_BEARING_MARTINELLI_CLOSED_FORM_H_
#define CALIB_SOLVERS_BEARING_MARTINELLI_CLOSED_FORM_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/status.h>
#include <calib/solvers/bearing/bearing_circle_fit.h>
#include <calib/solvers/bearing/martinelli_run_fit.h>

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

// Martinelli's closed-form bearing-only calibration (INRIA RR-6796, 2009, §6–7): per circular
// run at fixed q = vL/vR, ξq from the period of β(s), a node from the symmetry of β (Algorithm 1,
// eq. 35), L, c, k; then over ≥ 3 runs with distinct q the parameters φ, ψ, η, δ, ξ, and with an
// initial distance D0 also ρ, δR, δL, δB.
//
// Additions to the paper, all closed form. (1) On a circle, β(s) = θC + arg(1 + r·e^{iχ})
// (core/bearing_model.h, BearingCircle): for a trial ξq the condition "e^{iβj} ∥ a + b·e^{−iξq·sj}"
// is linear and homogeneous in the complex a, b, so the period is found by a 1-D search whose
// cost is the least eigenvalue of a 4×4 (generalized) eigenproblem, using every sample wherever
// it lies in s; the same eigenvector gives θC, r and the node exactly. Algorithm 1 and eq. 36 are
// still run and reported, and used instead with refine_with_all_samples = false. (2) The mod-2π
// form of eq. 35, β(s) + β(ŝ) = π − 2L, and the sign of the centre's direction fix L modulo π and
// ψ modulo 2π, which the paper's mod-π equations leave open. (3) ξ and δ by least squares over all
// runs, weighted by each ξq's variance.
namespace calib {

struct MartinelliEstimate {
  BearingParams params;                         // φ, ψ, η, δ, ξ.
  double eta_x_per_m = 0.0, eta_y_per_m = 0.0;  // η cos φ, η sin φ (§7).
  bool has_metric = false;                      // True when meta.json gave an initial distance.
  BearingMetricParams metric;                   // φ, ρ, ψ, δR, δL, δB.
  std::vector<MartinelliRunEstimate> runs;
  std::vector<int> skipped_runs;  // Non-circular runs (skip_non_circular_runs).
};

StatusOr<MartinelliEstimate> MartinelliClosedForm(const BearingLog& log,
                                                  const MartinelliOptions& options = {});

// The closed form on the bearings with keep[i][j] true (all when `keep` is null), as the seeding
// of CalibrateBearing uses it: the log is taken as valid (ValidateBearingLog), and an initial
// distance given for a run that is not a circle leaves the estimate without the metric set
// instead of failing.
StatusOr<MartinelliEstimate> MartinelliClosedFormOf(const BearingLog& log,
                                                    const std::vector<std::vector<bool>>* keep,
                                                    const MartinelliOptions& options);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_MARTINELLI_CLOSED_FORM_H_
