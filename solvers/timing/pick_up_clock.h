#ifndef CALIB_SOLVERS_TIMING_PICK_UP_CLOCK_H_
#define CALIB_SOLVERS_TIMING_PICK_UP_CLOCK_H_

#include <calib/core/timing/stream_samples.h>

#include <optional>
#include <vector>

// The clock of a free-running sensor read from pick-up stamps alone. A logger that stamps, at its
// own ticks, the latest sample holds sample floor((stamp − c)/P) for the sensor's period P and a
// phase c (the first sample's time plus the pick-up delay). So two distinct samples in a row must
// get increasing indices, and a held repeat (the same sample picked up again) the same one. Only
// the true (P, c) satisfy all of these: one microsecond off in P breaks them at dozens of samples
// of a 10⁴-sample log. The holds are needed: without them P = the logger's period, which never
// skips a sample, satisfies every constraint too.
namespace calib {

struct PickUpClock {
  double period_s = 0.0;
  double phase_s = 0.0;          // c, on the stamps' clock (relative to StreamSamples::origin_s).
  double period_stddev_s = 0.0;  // Of a uniform over the periods that break the fewest.
  int violations = 0;            // Constraints the best (P, c) breaks,
  int constraints = 0;           // of this many (one per record after the first).
  std::vector<double> indices;   // floor((stamp − c)/P) − that of the first sample, per sample.

  // At most 0.1 % of the constraints broken: the indices are taken as named (a broken one puts
  // one sample a period off, not every later one, and is left to the robust loss).
  bool NamesEverySample() const { return violations <= 0.001 * constraints; }
};

// Searches P within ±50 % of the stamps' median step, coarse to fine on growing prefixes of the
// log; for each P the best c comes from a sweep over the arcs of c each constraint forbids.
// Empty when there are fewer than 3 held repeats or more than 1 % of the constraints are broken
// (stamps that are not pick-up times of one free-running sensor). A few holds already pin P over
// a long log (each allows a few ms of phase in ~100): a logger with 2 ms of jitter holds ~5 of
// 1000 samples, and counting periods from the motion instead took 99.885 ms for 99.5 on one.
// The skips are then less pinned than P, but naming them still beats the motion's re-assignment.
//
// `motion_periods` (per sample k, between samples k − 1 and k; 0 where unknown): whole sensor
// periods the motion counts, which make m ticks in (from, to] a constraint too. A logger slower
// than its sensor never holds, but its skips (two periods of motion in one stamp step) pin P and
// c the same way, and between them, where the robot stood still, the clock names the skips the
// motion could not see. These counts then stand in for the holds (3 at least that differ from the
// stamps' step). `period_s` (0: the stamps' median step) centres the search: a logger much
// slower than its sensor steps by more than a period.
std::optional<PickUpClock> FitPickUpClock(const StreamSamples& data,
                                          const std::vector<int>& motion_periods = {},
                                          double period_s = 0.0);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_PICK_UP_CLOCK_H_
