#ifndef CALIB_SOLVERS_BEARING_MARTINELLI_RUN_FIT_H_
#define CALIB_SOLVERS_BEARING_MARTINELLI_RUN_FIT_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/status.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <string>
#include <vector>

// The per-run part of Martinelli's closed form (§5–7): a circular run's samples, Algorithm 1's
// node, and everything one circle determines (solvers/bearing/martinelli_closed_form.h combines
// the runs).
namespace calib {

struct MartinelliOptions {
  double min_periods = 0.9;           // Bearings must span this fraction of a period of β(s).
  double max_q_deviation = 0.02;      // Max |αL − q·αR| over the run, relative to max |αR|.
  double max_abs_q = 20.0;            // Beyond: the right wheel barely turns (s is its travel).
  double min_q_separation = 0.05;     // q values closer than this count as one.
  double min_parallax = 0.01;         // Min of |r| and 1/|r| (how much β deviates from rotation).
  int node_grid_points = 200;         // Algorithm 1's grid over half a period.
  int max_period_scan_samples = 400;  // Samples used in the coarse period scan.
  // δR, δL, δB are taken to lie within [1/f, f] of nominal; bounds the period search.
  double max_calibration_factor = 2.0;
  bool refine_with_all_samples = true;  // Node, L, k from all samples (else Algorithm 1, eq. 36).
  bool combine_wheels = true;  // s from both wheels' rotations projected on the fixed ratio q.
  bool skip_non_circular_runs = false;  // Else a run that is not at fixed q is an error.
};

// What one circular run determines (§5–7). s is the right wheel's nominal travel from the run's
// first encoder sample.
struct MartinelliRunEstimate {
  int run = 0;
  double q = 0.0;  // vL/vR from the encoders.
  int num_bearings = 0;
  double periods_covered = 0;  // Span of the bearings in s over 2π/|ξq|.
  BearingCircle circle;        // ξq, node, θC, r: β(s) in closed form.
  double xi_q_per_m = 0.0;     // Eq. 31 (sign included: the sense of the landmark's apparent turn).
  double node_m = 0.0;         // A node (eq. 26): β is symmetric about it (eq. 34–35).
  double node_algorithm1_m = 0.0;      // Algorithm 1's node, refined below its grid step.
  double spread_algorithm1_rad = 0.0;  // σ(s_n) of Algorithm 1 (circular std of β(s) + β(ŝ)).
  double l_rad = 0.0;  // L (eq. 15), in (ψ − π/2, ψ + π/2] as its definition implies.
  double l_algorithm1_rad = 0.0;       // L from eq. 35 at Algorithm 1's node, same branch.
  double k_per_m = 0.0;                // Eq. 17.
  double k_mirror_points_per_m = 0.0;  // Eq. 36 from the bearings at two mirror points.
  double c_rad = 0.0;                  // Eq. 21, consistent with the node through eq. 26 for s_w.
  int s_w = 1;
  std::array<double, 2> c_candidates_rad{};  // Eq. 26 for S_w = +1, −1, in (−π/2, π/2].
  double a0 = 0.0, v0 = 0.0;                 // A and V (eq. 15) at s = 0.
  double mu0 = 0.0, gamma0_rad = 0.0;        // μ and γ (eq. 3) at s = 0.
  double rms_residual_rad = 0.0;             // Bearing residual of the fitted circle.
  // Covariance of (ξq, node, θC, r) from the residuals (first order, s taken as exact).
  Eigen::Matrix4d circle_covariance = Eigen::Matrix4d::Zero();
  double parallax = 0.0;  // min(|r|, 1/|r|).
};

// A circular run's samples: q, and for each bearing s (m) and β (rad). `circle` is false (with
// the reason in `not_circle`) when the wheels depart from a fixed ratio q: not an error, since
// the closed form may skip such runs (MartinelliOptions::skip_non_circular_runs).
struct CircularRunSamples {
  int run = 0;
  double q = 0.0;
  double q_deviation = 0.0;  // Max |αL − q·αR| / max |αR|.
  bool circle = true;
  std::string not_circle;
  std::vector<double> s_m;
  std::vector<double> bearing_rad;
};
// With `keep` (one flag per bearing of the run) only the kept bearings are sampled.
StatusOr<CircularRunSamples> ExtractCircularRun(const BearingRun& run, double wheel_radius_m,
                                                const MartinelliOptions& options = {},
                                                const std::vector<bool>* keep = nullptr);

// Algorithm 1: the node s_c in [s_min, s_min + π/|ξq|) minimising the spread of
// β(s) + β(2s_c − s) over the samples (β at 2s_c − s by periodic linear interpolation), refined
// below the grid step. `symmetric_sum_rad` is the circular mean of the sums, 2θC = π − 2L.
struct NodeSearch {
  double node_m = 0.0;
  double spread_rad = 0.0;
  double symmetric_sum_rad = 0.0;
  int pairs = 0;
};
StatusOr<NodeSearch> FindNodeAlgorithm1(const std::vector<double>& s_m,
                                        const std::vector<double>& bearing_rad, double xi_q_per_m,
                                        int grid_points = 200);

// What one circular run determines alone (L provisional, mod π, until ψ is known).
StatusOr<MartinelliRunEstimate> FitCircularRun(const CircularRunSamples& samples,
                                               double wheelbase_m,
                                               const MartinelliOptions& options);

// The representative of x modulo `period` nearest to `target`.
inline double NearestModulo(double x, double period, double target) {
  return x + period * std::round((target - x) / period);
}

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_MARTINELLI_RUN_FIT_H_
