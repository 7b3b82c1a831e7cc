#ifndef CALIB_SOLVERS_TIMING_CLOCK_INDICES_H_
#define CALIB_SOLVERS_TIMING_CLOCK_INDICES_H_

#include <calib/core/timing/stream_samples.h>
#include <calib/solvers/timing/latent_time_problem.h>

#include <vector>

// Which sample of a free-running sensor each pick-up stamp holds. A logger stamps at pick-up the
// latest sample, taken in [s − c − P, s − c) (c its fixed delay): given the clock, the stamps name
// the samples, except within the clock's error of the window's edges. When the logger and the
// sensor run at nearly the same period the lag sweeps slowly across the window, and a run of
// samples there is ambiguous: a skip put a few samples early or late shifts them all by a period.
// The motion settles it: an interval given one period too few or too many moves twice or half
// as far as the wheels say.
namespace calib {

// Indices from the lags about the clock `s.clock` (c a low quantile of the lags), then each moved
// by at most one where that fits the motion better: a dynamic programme over the samples with
// offsets {−1, 0, +1}, increasing indices, the cost a penalty on lags outside the window (in
// units of 2 % of the period) plus the robust (Cauchy, scale 3) whitened misfit of every
// interval's measured motion against the wheels' at the calibration `s.calibration`.
std::vector<double> ReassignClockIndices(const StreamSamples& data, const LatentTimeState& s);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_CLOCK_INDICES_H_
