#ifndef CALIB_SOLVERS_SCAN_MATCHING_LINE_NOISE_BIAS_H_
#define CALIB_SOLVERS_SCAN_MATCHING_LINE_NOISE_BIAS_H_

#include <Eigen/Core>

// The bias that range noise puts in a point-to-line match (errors in variables). For one pair,
// r = n·(R p + t − q_a) with n the unit normal of the reference line through q_a and q_b and
// J = ∂r/∂(t, θ) = (n, n·(R p)^⊥): E[J r] at the true pose, to second order in the range noise
// σ of q_a, q_b (along their beams u_a, u_b) and of p (along R u_p). The least-squares pose of
// many pairs follows the summed bias by H⁻¹ Σ E[J r], which the matcher takes out.
//
// A reference range z_k tilts the line (∂n/∂z_k = ∓(n·u_k) τ/ℓ, τ = (q_b − q_a)/ℓ) and moves the
// residual (∂r/∂z_b = −α n·u_b, ∂r/∂z_a = −(1 − α) n·u_a, α the foot's place on the segment),
// so J and r share its noise; r is also curved in z_k (∂²r/∂z_b² = 2α(n·u_b)(τ·u_b)/ℓ,
// ∂²r/∂z_a² = −2(1 − α)(n·u_a)(τ·u_a)/ℓ), so E[r] ≠ 0; and p's range moves both r and J_θ.
// With s_b = α, s_a = −(1 − α) and T = (τ, τ·(R p)^⊥):
//   E[J r] = σ²/ℓ Σ_k s_k (n·u_k) [(n·u_k) T + (τ·u_k) J] + σ² (n·R u_p)(0, 0, τ·R u_p).
// On dense scans with cm of noise (lines of ~10 cm) the pose's bias is ~0.1 mm per match and
// follows the turn, which a calibration over thousands of matches reads as a lateral mounting
// offset.
namespace calib {

// `rotated_point` is R p, `rotated_direction` R u_p; `alpha` the foot's place, (P − q_a)·τ/ℓ.
Eigen::Vector3d LineNoiseGradientBias(const Eigen::Vector2d& qa, const Eigen::Vector2d& qb,
                                      const Eigen::Vector2d& ua, const Eigen::Vector2d& ub,
                                      double alpha, const Eigen::Vector2d& rotated_point,
                                      const Eigen::Vector2d& rotated_direction, double sigma_m);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_LINE_NOISE_BIAS_H_
