#ifndef CALIB_SOLVERS_TIMING_CLOCK_START_H_
#define CALIB_SOLVERS_TIMING_CLOCK_START_H_

#include <calib/core/timing/stream_samples.h>
#include <calib/solvers/timing/pick_up_clock.h>
#include <calib/solvers/timing/timing_model_fit.h>

#include <optional>

// Where the free-running clock model starts from, and whether to try it, given a fit of the stamp
// model.
namespace calib {

// Whether the stamp model's sample times rule out any sensor clock: its jitter is under a tenth
// of the period (the times sit near the stamps), yet counting whole periods between them, they
// stray from the best regular grid by more than a period (steps that vary and add up: a sensor
// triggered by something else). A clock's samples picked up late stay within about a period of
// their grid; such a log only costs the clock model's rounds, which then never settle. (The
// caller asks only where no holds or counted skips named the clock's samples.)
bool TimesStrayFromEveryClock(const StreamSamples& data, const TimingModelFit& stamps);

// Whether the stamps count the sensor's periods: steps within 5 % of whole periods that stay
// within half a period of one regular grid (an irregular sampler's steps near 1 period add up
// and stray from it), no held repeats, and the motion (wheels at `state`'s calibration against
// the measured motion) confirms the steps (no skipped samples, under 5 % of the intervals
// disagreeing). The clock's indices are then the stamps' own, and the clock model needs no stamp
// model to start from.
bool StampsCountSensorPeriods(const StreamSamples& data, const LatentTimeState& state);

// The pick-up clock that the skips the motion counts name (FitPickUpClock), the motion at
// `state`'s calibration; empty where the stamps count the periods or it names not every sample.
// A logger slower than its sensor holds nothing, and the stamp model's latent times blur its
// skips (its scan noise took them in: no interval stayed trusted), so the count is taken at the
// stamp-as-truth fit.
std::optional<PickUpClock> MotionCountedPickUpClock(const StreamSamples& data,
                                                    const LatentTimeState& state);

// The clock model's starting point from a fit of the stamp model: whole periods per interval
// (from the stamps where they sit on the period's grid and the motion agrees; pick-up stamps with
// held repeats, or skips the motion counts over steady stretches, name them exactly through
// FitPickUpClock, and are then never re-assigned; else from the ratio of measured to wheel
// motion), the clock fitted to the stamps, indices re-assigned from them, and for stamps on the
// grid a stamp prior (τ, σ_s) from their scatter about the clock.
// `pick_up`: FitPickUpClock's result when the caller has it already.
LatentTimeState ClockStartFromTimes(const StreamSamples& data, const TimingModelFit& stamps,
                                    const std::optional<PickUpClock>& pick_up = std::nullopt);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_CLOCK_START_H_
