#ifndef CALIB_SOLVERS_BEARING_BEARING_SEED_SEARCH_H_
#define CALIB_SOLVERS_BEARING_BEARING_SEED_SEARCH_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/status.h>

#include <Eigen/Core>
#include <vector>

// The seeds of the bearing bundle adjustment that need no circles: a coarse search for the
// calibration on arbitrary trajectories, and the landmark's place in each run's start frame.
// Both take an optional selection keep[i][j] of the bearings to use (all when null): the seeding
// leaves gross outliers out.
namespace calib {

struct BearingSearchOptions {
  // Ranges searched for δ = δL/δR and ξ·B = δR/δB (log-uniform).
  double min_delta = 0.8;
  double max_delta = 1.25;
  double min_xi_b = 2.0 / 3.0;
  double max_xi_b = 1.5;
  // Grid steps turn the dead-reckoned heading by at most this anywhere in a run.
  double heading_tolerance_rad = 0.15;
  int max_grid_points = 20000;    // Coarser steps beyond.
  int max_search_bearings = 300;  // The grid uses every k-th bearing to stay within this.
  int candidates = 4;             // Grid minima refined on every bearing.
  int refine_levels = 5;          // 5×5 refinements, the step halving each time.
  int num_threads = 1;            // Grid points evaluated in parallel.
};

// The landmark's position in each run's start frame (gauge units) for a given calibration: with
// dead-reckoned sensor positions s_j and measured directions d_j, cross(L − s_j, d_j) = 0 is linear
// in L; solved by least squares, reweighted by 1/|L − s_j|² so that residuals are angles.
StatusOr<std::vector<Eigen::Vector2d>> SeedLandmarks(
    const BearingLog& log, const BearingParams& params,
    const std::vector<std::vector<bool>>* keep = nullptr);

// A calibration for arbitrary trajectories. For trial (δ, ξ) each run's path (p_j, θ_j) is
// dead-reckoned from its first bearing, and the bearing condition
//   cross(L − p_j − R(θ_j)·m, R(c + θ_j)·u(β_j)) = 0,   c = φ + ψ,  m = ρ(cos φ, sin φ),
// with L the landmark in that frame, reads, with Q = R(−c − π/2) and w_j = R(θ_j)·u(β_j):
//   (Q·L)·w_j − (Q·m)·u(β_j) + cos c·cross(p_j, w_j) + sin c·(p_j·w_j) = 0,
// linear and homogeneous in (Q·L per run, Q·m, cos c, sin c). Eliminating Q·L and Q·m, the
// constraint cos²c + sin²c = 1 leaves a 2×2 eigenproblem (rows reweighted by 1/distance² so that
// they measure angles); the fit is scored by its bearing errors. (δ, ξ) come from a grid whose
// steps turn the dead-reckoned heading by at most `heading_tolerance_rad` (the information on
// them is the long-range agreement of odometry heading and bearings, so the basin is that
// narrow), then from local refinement of the best minima. Validates the log.
StatusOr<BearingParams> SearchBearingSeed(const BearingLog& log,
                                          const BearingSearchOptions& options = {});
// The same on a log already validated, with the bearings keep[i][j] (all when null).
StatusOr<BearingParams> SearchBearingSeedOf(const BearingLog& log,
                                            const std::vector<std::vector<bool>>* keep,
                                            const BearingSearchOptions& options);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_SEED_SEARCH_H_
