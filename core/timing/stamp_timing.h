#ifndef CALIB_CORE_TIMING_STAMP_TIMING_H_
#define CALIB_CORE_TIMING_STAMP_TIMING_H_

#include <calib/core/status.h>

#include <string>
#include <vector>

// Timing diagnostics of one logged stream from its stamps (and, optionally, its values) alone:
// is each stamp the time the sample was taken, or the time a logger picked it up?
//
// Model: stamp_k = t0 + n_k·P + drift + e_k, with n_k integers that skip missed samples and e_k
// the stamp scatter. A sensor stamped at its own sample times gives small e_k; a logger that
// stamps at pick-up gives scatter about its own poll grid, and when the sensor free-runs at its
// own period the logged values come in whole sensor steps (0 = the same sample picked up again,
// 2 = one sample skipped) while the stamps say otherwise.
namespace calib {

struct StreamTiming {
  std::string stream;  // "odometry", "sensor_poses", "bearings".
  std::string source;  // File, for messages.
  int records = 0;     // As read.
  int samples = 0;     // After dropping exact duplicate records.
  int duplicates_dropped = 0;
  // Consecutive records with identical values but a later stamp, isolated inside motion (the
  // step after is a catch-up of at least 1.5 typical steps): a held sample picked up again. Runs
  // of identical values at rest are not counted.
  int repeated_values = 0;
  double period_s = 0;  // Base period of the stamps.
  // Robust scatter (1.4826·MAD) of the stamps about the best regular grid t0 + n_k·P, fitted
  // robustly per window of 40 samples (so drift and a long log do not inflate it), corrected
  // for the two fitted grid parameters.
  double jitter_s = 0;
  int gaps = 0;              // Stamp intervals longer than 5 periods (not counted as multiples).
  double longest_gap_s = 0;  // The longest stamp interval (0 when there is no gap).
  double multiple_fraction = 0;  // Fraction of non-gap intervals near k·P with k ≥ 2.
  bool regular = false;          // jitter_s ≤ 2 % of the period.
  // Intervals cluster at multiples of the base period (≥ 25 % at k ≥ 2: an unrelated pick-up
  // clock), held samples repeat (≥ 2), and/or displacement steps come in multiples of one step.
  bool free_running_signature = false;
  // False when the diagnostics show the stamps cannot be the sample times: a free-running
  // signature, or a stamp scatter above 5 % of the period whose consecutive intervals are
  // anti-correlated (the signature of scatter added to a grid, not of an irregular sampler).
  bool stamps_are_sample_times = true;
  std::vector<std::string> notes;  // One sentence each, for a person.

  // Added detail.
  int intervals = 0;  // Positive stamp intervals between samples.
  // Lag-1 correlation of consecutive interval deviations from n_k·P: −0.5 for white scatter
  // about a grid, 0 for an irregular sampler whose intervals are independent.
  double interval_correlation = 0;
  // White scatter of the stamps implied by that correlation: sqrt(−cov(δ_k, δ_{k+1})).
  double pickup_scatter_s = 0;
  int steady_steps = 0;  // Displacement steps in steady windows (AnalyzeDisplacementSteps).
  double step_multiple_fraction = 0;     // Of those, the fraction off the window's usual multiple.
  bool step_multiples_detected = false;  // StepMultiples::detected.
  bool values_quantized = false;         // Values move in whole ticks: steps were not analysed.
};

struct StepMultiples {
  int steady_steps = 0;  // Steps in windows explained by one unit step.
  int zero_steps = 0;    // ≈ 0 units: the same sample picked up again.
  int multi_steps = 0;   // ≈ k ≥ 1 units but not the window's usual (mode) multiple.
  // (zero + multi) / steady: steps off their window's usual multiple of the unit.
  double multiple_fraction = 0;
  bool detected = false;  // At least 3 such steps, ≥ 0.25 %, in ≥ 20 steady steps.
};

// The constant-speed signature from the values: in windows of 8 consecutive steps where every
// step length is within 15 % of a whole multiple (0..4) of one unit u > 0 (u = the median
// non-zero step / n, n = 1..3, the first that fits), every zero step is isolated and followed
// by a catch-up of ≥ 2 units (steady motion, not a start or a stop), the steps at the window's
// usual multiple agree to 10 % and every run off it is interior, at most 3 steps and within one
// unit of the usual pace (a skip or a hold, not a change of speed), counts the steps off the
// window's most common multiple: held (0) or skipped (one more or less) sensor samples.
// `step_lengths[k]` is the length of the displacement from record k to k + 1 (any consistent norm);
// `stamps_s` (one more than step_lengths) is kept for future use of the intervals and must match in
// size.
StepMultiples AnalyzeDisplacementSteps(const std::vector<double>& stamps_s,
                                       const std::vector<double>& step_lengths);

// Analyses one stream as read: `stamps_s` in file order (non-decreasing; decreasing intervals are
// skipped, the readers reject them first); `values_row_major` optionally holds the record values
// (values.size() a multiple of stamps.size(); else ignored). Consecutive records with the same
// stamp and the same values (or the same stamp when no values are given) are exact duplicates:
// counted and dropped. With values, also counts held repeats and runs AnalyzeDisplacementSteps
// on the Euclidean norm of consecutive value differences. Fills every field and the notes.
StreamTiming AnalyzeStreamTiming(const std::vector<double>& stamps_s,
                                 const std::vector<double>& values_row_major = {},
                                 const std::string& stream = "", const std::string& source = "");

// Folds step multiples into a timing (fields, signature, verdict and notes), for callers that
// measure displacement steps themselves.
void AddStepMultiples(const StepMultiples& steps, StreamTiming* timing);

// One timing for several runs of the same stream (bearing logs): counts, gaps and steps summed;
// period the sample-weighted mean; jitter the root of the sample-weighted mean square; flags
// OR-ed (sample times only if every run's are); notes of the pooled figures, naming the runs
// count, plus every run's own notes that flag a problem.
StreamTiming PoolStreamTiming(const std::vector<StreamTiming>& runs, const std::string& stream,
                              const std::string& source);

// A stream's records in file order, for the readers' duplicate handling.
struct StreamRecords {
  std::vector<double> stamps_s;
  std::vector<double> values;            // Row-major, value_names.size() per record.
  std::vector<int> lines;                // 1-based source lines (empty: not from a file).
  std::vector<std::string> value_names;  // "left", "right": named in messages.
};

// Stamps in seconds, as every reader wants them: a median step over kMaxStampStepS (no robot's
// encoders, scans or bearings come that rarely) or a stamp beyond 1e14 (nanoseconds since 1970)
// is an error naming `source` and the unit the stamps look like (ms, µs or ns: the first that
// brings the median step within 10 s). Too few stamps to tell: Ok. `field` names the column.
inline constexpr double kMaxStampStepS = 10.0;
Status CheckStampUnit(const std::vector<double>& stamps_s, const std::string& source,
                      const std::string& field = "t");

// Drops consecutive exact duplicates (same stamp, same values) from `records`; `dropped` (may be
// null) receives how many. A repeated stamp with different values is an error naming both lines and
// the first differing value ("odometry.csv: line 12 and line 13 share t=3.2 but differ in left").
// Order is not checked here.
Status DropExactDuplicates(const std::string& source, StreamRecords* records,
                           int* dropped = nullptr);

}  // namespace calib

#endif  // CALIB_CORE_TIMING_STAMP_TIMING_H_
