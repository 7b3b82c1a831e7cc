#ifndef CALIB_SOLVERS_BEARING_BEARING_TIMING_H_
#define CALIB_SOLVERS_BEARING_BEARING_TIMING_H_

#include <calib/solvers/bearing/bearing_clock.h>

#include <string>
#include <vector>

// The timing model of the bearing calibration (issue 10, item 6): the bearing stamped t_k was
// taken at t_k + τ + ε_k on the encoder clock, τ a common offset and ε_k ~ N(0, σ_t²) a jitter.
// τ enters the bundle adjustment exactly (problems/bearing/bearing_time_offset_residual.h: the pose
// advanced by the encoders over [t_k, t_k + τ]); ε_k to first order, as a bearing error of variance
// σt²·(dβ̂/dt)² added to σβ² (BearingNoise::bearing_jitter_s), dβ̂/dt by autodiff of the same
// term. Scatter of the encoder stamps enters the same way: the pose at a bearing time is
// interpolated between two encoder samples, so their stamp errors move it along the path by
// (1 − f)·ε_a + f·ε_b, which the bearing sees as a timing error of that size; σ_t is the scatter
// of the bearing times relative to the encoder clock, whichever stream it comes from.
// A free-running bearing sensor stamped at pick-up (solvers/bearing/bearing_clock.h) is a third
// part: its clock replaces the stamps when a screen of the final fit finds it and the re-fit on
// the clock's times confirms it. Each part is kept only when the data ask for it
// (likelihood-ratio tests); otherwise the calibration is exactly the plain one.
namespace calib {

struct BearingTimingOptions {
  bool time_offset = true;        // Test τ and model it when significant.
  bool stamp_jitter = true;       // Test σ_t and model it when significant.
  bool sensor_clock = true;       // Screen for a free-running bearing clock and re-fit on it.
  bool keep_time_offset = false;  // Model τ whatever its test says (the clock's re-fit).
  double significance = 0.01;     // Level of each likelihood-ratio test.
};

// σ_t by profile likelihood over the bearing errors e_k (inliers), with rates g_k = dβ̂/dt:
//   ℓ(σ_t) = max over σβ of −½Σ[log v_k + ẽ_k²/v_k],   v_k = σβ² + σ_t²·g_k²,
// ẽ_k = e_k/√f with f = Σ(1 − h)/n the residuals' shrinkage by their leverage. The test of
// σ_t = 0 is on the boundary: LR ~ ½χ²₀ + ½χ²₁. The σ of σ_t from the profile's curvature.
struct BearingJitterEstimate {
  double jitter_s = 0.0;
  double jitter_stddev_s = 0.0;
  double bearing_sigma_rad = 0.0;                 // σβ at σ_t = jitter_s.
  double bearing_sigma_without_jitter_rad = 0.0;  // σβ at σ_t = 0.
  double lr_statistic = 0.0;
  double p_value = 1.0;
  bool significant = false;
  int bearings_used = 0;
};
BearingJitterEstimate EstimateBearingJitter(const std::vector<double>& errors_rad,
                                            const std::vector<double>& rates_rad_per_s,
                                            double redundancy_fraction, double significance);

// What the calibration modelled of the timing, for the report's "timing" object.
struct BearingTiming {
  bool time_offset_tested = false;
  bool time_offset_modelled = false;
  double time_offset_s = 0.0;         // In the calibration (0 when not modelled).
  double time_offset_stddev_s = 0.0;  // Of the free estimate (how well the log bounds τ).
  double time_offset_free_s = 0.0;    // τ estimated freely, whether kept or not.
  double time_offset_lr = 0.0;
  double time_offset_p_value = 1.0;
  bool jitter_tested = false;
  bool jitter_modelled = false;
  BearingJitterEstimate jitter;
  // The free-running clock estimated on the stamps' fit, and the re-fit on its times: −2 log L of
  // its σβ over the stamps' (before either models τ or jitter); the clock is kept unless that is
  // significantly positive.
  BearingClockEstimate clock;
  bool clock_modelled = false;
  double clock_confirm_lr = 0.0;
  double clock_confirm_p_value = 1.0;
  int held_bearings_dropped = 0;         // Held samples picked up again (modelled clock only).
  int bearings_before_encoders = 0;      // Clock times before the run's first encoder sample.
  double plain_bearing_sigma_rad = 0.0;  // σβ of the fit before τ and jitter.
  std::string treatment = "stamps as sample times";  // What the estimate models.
  std::string statement;                             // One sentence for a person.
};

// The treatment's words from what was modelled.
std::string BearingTimingTreatment(const BearingTiming& timing);
std::string BearingTimingStatement(const BearingTiming& timing);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_TIMING_H_
