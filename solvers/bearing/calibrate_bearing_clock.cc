// The free-running bearing clock in CalibrateBearing (solvers/bearing/bearing_clock.h): estimated
// on the fit that took the stamps as sample times, then the calibration re-run on the clock's
// times and kept unless its bearing noise is significantly worse.
#include <calib/solvers/bearing/bearing_text.h>
#include <calib/solvers/bearing/calibrate_bearing_internal.h>
#include <calib/solvers/stats/score_test.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace calib::bearing_calibration {
namespace {

// The clock's input from the fit: per run the bearings that are not held repeats, with the
// fit's rates and inlier flags. `held` counts the repeats.
std::vector<BearingClockRun> ClockRunsAtFit(const BearingLog& log, const BearingProblem& problem,
                                            const BearingMask& inlier, int* held) {
  std::vector<BearingClockRun> runs(log.runs.size());
  const std::vector<double> rates = problem.BearingRates();
  const std::vector<BearingProblem::BearingTermInfo> terms = problem.BearingTerms();
  *held = 0;
  for (size_t t = 0; t < terms.size(); ++t) {
    const int i = terms[t].run, k = terms[t].bearing;
    if (IsHeldBearing(log.runs[i], k)) {
      ++*held;
      continue;
    }
    runs[i].stamps_s.push_back(log.runs[i].bearings[k].t_s);
    runs[i].bearings_rad.push_back(log.runs[i].bearings[k].bearing_rad);
    runs[i].rates_rad_per_s.push_back(rates[t]);
    runs[i].inlier.push_back(inlier[i][k]);
  }
  return runs;
}

// The log on the clock's times: held repeats dropped, each bearing of a run with a clock at
// t0 + P·n (those before the run's first encoder sample dropped and counted).
BearingLog RetimedLog(const BearingLog& log, const BearingClockEstimate& clock, int* held,
                      int* before) {
  BearingLog out = DropHeldBearings(log, held);
  out.stream_timing.clear();  // The stamps' warnings are the outer calibration's.
  *before = 0;
  for (size_t i = 0; i < out.runs.size(); ++i) {
    BearingRun& run = out.runs[i];
    if (!(clock.clocks[i].period_s > 0.0) || run.bearings.empty()) continue;
    std::vector<double> stamps;
    for (const BearingSample& b : run.bearings) stamps.push_back(b.t_s);
    const std::vector<double> times = BearingClockTimes(stamps, clock.clocks[i]);
    std::vector<BearingSample> kept;
    for (size_t k = 0; k < times.size(); ++k) {
      if (times[k] < run.odometry.front().t_s) {
        ++*before;
        continue;
      }
      kept.push_back(run.bearings[k]);
      kept.back().t_s = times[k];
    }
    run.bearings = std::move(kept);
  }
  return out;
}

}  // namespace

StatusOr<BearingCalibrationResult> TrySensorClock(
    const BearingLog& log, const BearingCalibrationOptions& options, const Progress& progress,
    const BearingProblem& problem, const BearingMask& inlier, BearingCalibrationResult stamps) {
  BearingTiming& timing = stamps.timing;
  int held = 0;
  const std::vector<BearingClockRun> runs = ClockRunsAtFit(log, problem, inlier, &held);
  timing.clock = EstimateBearingClock(runs, problem.noise().bearing_sigma_rad, held);
  if (!timing.clock.tested) return stamps;
  progress("sensor clock: period " + Num(timing.clock.period_s * 1e3, 6) + " ± " +
           Num(timing.clock.period_stddev_s * 1e3, 2) + " ms against stamp steps of " +
           Num(timing.clock.stamp_step_s * 1e3, 6) + " ms; " + std::to_string(held) + " held and " +
           std::to_string(timing.clock.skipped_samples) + " skipped samples");
  if (!timing.clock.free_running || !timing.clock.period_determined) return stamps;
  BearingCalibrationOptions nested = options;
  nested.timing.sensor_clock = false;
  nested.timing.keep_time_offset = true;  // Its σ carries the common phase's.
  int dropped = 0, before = 0;
  const BearingLog retimed = RetimedLog(log, timing.clock, &dropped, &before);
  StatusOr<BearingCalibrationResult> clock = CalibrateBearing(retimed, nested);
  if (!clock.ok()) {
    progress("sensor clock: the re-fit on the clock's times failed: " + clock.message());
    timing.clock_confirm_p_value = 0.0;
    return stamps;
  }
  // The clock is kept unless it explains the bearings significantly worse than the stamps did
  // (−2 log L of the fits before τ and jitter: n·log σβ² each).
  const double ratio = clock->timing.plain_bearing_sigma_rad / timing.plain_bearing_sigma_rad;
  timing.clock_confirm_lr = clock->inliers * 2.0 * std::log(ratio);
  const int dof = static_cast<int>(retimed.runs.size()) + 1;
  timing.clock_confirm_p_value =
      timing.clock_confirm_lr > 0.0 ? ChiSquareSurvival(timing.clock_confirm_lr, dof) : 1.0;
  progress("sensor clock: re-fit σβ " + Num(clock->timing.plain_bearing_sigma_rad * 180 / M_PI, 3) +
           "° against " + Num(timing.plain_bearing_sigma_rad * 180 / M_PI, 3) + "° on the stamps");
  if (timing.clock_confirm_p_value <= options.timing.significance) return stamps;
  BearingCalibrationResult out = std::move(*clock);
  out.timing.clock = timing.clock;
  out.timing.clock_modelled = true;
  out.timing.clock_confirm_lr = timing.clock_confirm_lr;
  out.timing.clock_confirm_p_value = timing.clock_confirm_p_value;
  out.timing.held_bearings_dropped = dropped;
  out.timing.bearings_before_encoders = before;
  out.timing.treatment = BearingTimingTreatment(out.timing);
  out.timing.statement = BearingTimingStatement(out.timing);
  return out;
}

}  // namespace calib::bearing_calibration
