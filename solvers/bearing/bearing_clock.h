#ifndef CALIB_SOLVERS_BEARING_BEARING_CLOCK_H_
#define CALIB_SOLVERS_BEARING_BEARING_CLOCK_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/timing/sample_clock.h>

#include <vector>

// A free-running bearing sensor whose samples a logger stamps when it picks them up (issue 10,
// item 6; the laser's clock model in solvers/timing, here for the bearings). Sample n of run i is
// taken at t_i(n) = t0_i + P·n on the sensor's clock (core/timing/sample_clock.h), one period P
// for the log and one phase t0_i per run; the logger writes the latest sample at its pick-up s,
// so the bearing stamped s was taken at t(n), n = ⌊(s − t0_i)/P⌋: up to one period early. The lag
// sweeps across the period as the two clocks beat (a sawtooth, neither a constant offset nor a
// white jitter), and a sample the logger missed leaves no trace in the stamps. Held samples
// (picked up twice) repeat the bearing exactly and are dropped before indices are assigned.
//
// Indices. Where the model's bearing rate g makes one period's change g·P stand far above the
// noise, the bearing's own step counts the periods between two rows (1; 2 where the logger
// missed a sample, which its stamps do not show); elsewhere the stamp step does. P is then the
// least-squares slope of the stamps against those indices over the stretches counted by the
// bearings (the pick-up lags average out), each run's phase the lower envelope of s − P·n (a lag
// is never negative), and every index re-assigned from the stamps on that clock
// (ClockIndicesFromStamps). The stamps' own step says nothing of P when the logger is slower than
// the sensor: a time scale off by P/step − 1 acts on the bearings as a scale of the wheels' turn
// rate, which is why it biases ξ while the residuals look like noise.
//
// The clock is adopted when the log shows it and fixes P (BearingClockEstimate::period_determined)
// and the calibration re-fitted on its times (calibrate_bearing_clock.cc) does not explain the
// bearings worse. A free-running sensor whose period the log cannot fix is a warning.
namespace calib {

// One run's bearings in log order, held repeats removed.
struct BearingClockRun {
  std::vector<double> stamps_s;
  std::vector<double> bearings_rad;
  std::vector<double> rates_rad_per_s;  // dβ̂/dt at the stamps-as-times fit.
  std::vector<bool> inlier;             // Of that fit.
};

struct BearingClockEstimate {
  bool tested = false;        // Enough bearings counted by their steps to fit P.
  double stamp_step_s = 0.0;  // Median stamp step.
  double period_s = 0.0;
  double period_stddev_s = 0.0;
  std::vector<SampleClock> clocks;  // Per run (period 0: none, stamps kept).
  int counted_steps = 0;            // Steps counted by the bearings.
  // Steps of two or more periods under one stamp step; they show the clock only beyond what the
  // bearings' noise makes of that many counted steps (p < 10⁻³).
  int skipped_samples = 0;
  int held_samples = 0;       // Rows that repeat their predecessor (the caller's count).
  bool free_running = false;  // Held or skipped samples show a free-running sensor.
  // The indices, hence P, are fixed by the log: the logger picks up every sample (held repeats
  // on ≥ 10 % of the rows) or the bearings counted the samples it missed. Otherwise the stamps'
  // step may differ from P unseen, and the clock is not modelled.
  bool period_determined = false;
};

// `sigma_rad` the bearing noise of the fit; `held` the repeats removed from the runs.
BearingClockEstimate EstimateBearingClock(const std::vector<BearingClockRun>& runs,
                                          double sigma_rad, int held);

// Sample times of the bearings stamped `stamps_s` on `clock`: t0 + P·n, n from the stamps
// (ClockIndicesFromStamps).
std::vector<double> BearingClockTimes(const std::vector<double>& stamps_s,
                                      const SampleClock& clock);

// Bearing k of the run repeats its predecessor's value exactly: a held sample picked up again.
bool IsHeldBearing(const BearingRun& run, size_t k);

// The log with each bearing that repeats its predecessor's value exactly (a held sample picked up
// again) removed; `dropped` counts them.
BearingLog DropHeldBearings(const BearingLog& log, int* dropped);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_CLOCK_H_
