#ifndef CALIB_CORE_TIMING_LOGGING_MODEL_H_
#define CALIB_CORE_TIMING_LOGGING_MODEL_H_

#include <calib/core/random.h>
#include <calib/core/status.h>

#include <cstddef>
#include <vector>

// How a real robot logs its sensors, for the simulators: the stamps a logger writes are not the
// times the samples were taken. A sensor free-runs on its own clock; a logger picks up the latest
// sample at its own (jittery) times and stamps it with the pick-up time; encoder polls scatter
// about their period and are stamped with more scatter; some records are written twice.
// All fields zero: every sample is written once, stamped with its true time.
namespace calib {

struct LoggingModel {
  // > 0: the sensor free-runs; sample k is taken at phase + k·period·(1 + drift) (true clock).
  // 0: the sensor samples at the simulator's own scan times.
  double sensor_period_s = 0.0;
  double sensor_phase_s = 0.0;
  double sensor_clock_drift = 0.0;  // Relative rate error of the sensor's clock, e.g. 2e-4.
  // > 0: at each pick-up u_i = u_0 + i·period + jitter the logger writes the latest sample taken
  // at or before u_i − latency, stamped u_i (a sample is written twice when the logger is faster
  // than the sensor, skipped when slower). 0: every sample is written once, stamped
  // t_k + latency + jitter.
  double logger_period_s = 0.0;
  double logger_jitter_s = 0.0;   // σ of the pick-up times (or of the stamps, without a logger).
  double pickup_latency_s = 0.0;  // Fixed delay before a sample can be picked up.
  // > 0: the encoders are polled at j·period + poll jitter (true times) and stamped with a further
  // scatter; 0: polled exactly at the sensor's sample times (stamp jitter still applies).
  double encoder_period_s = 0.0;
  double encoder_poll_jitter_s = 0.0;   // σ of the true poll times about j·period.
  double encoder_stamp_jitter_s = 0.0;  // σ of the stamps about the true poll times.
  double repeat_fraction = 0.0;         // Share of records written twice (exact duplicate rows).

  bool IsClean() const;  // Every field zero.
};

// Field-by-field checks (finite, non-negative, jitters small enough to keep stamps increasing,
// repeat_fraction < 0.5, |drift| < 0.01); the message names the field.
Status ValidateLoggingModel(const LoggingModel& model);

// The truth of a logged log: for every written row, the true time of the sample it holds.
struct LoggedTimingTruth {
  std::vector<double> sensor_sample_time_s;       // Per sensor row.
  std::vector<size_t> sensor_sample_index;        // Per sensor row: which sensor sample (0-based).
  std::vector<double> encoder_sample_time_s;      // Per encoder row: the true poll time.
  std::vector<double> all_sensor_sample_times_s;  // Every sample the sensor took, logged or not.
  size_t sensor_duplicates = 0;                   // Rows that repeat the previous row exactly.
  size_t encoder_duplicates = 0;                  // (the same in the encoder stream).
  size_t skipped_samples = 0;                     // Sensor samples never written.
  size_t held_samples = 0;  // Sensor rows that repeat a sample under a new stamp.
};

// Sample k of a free-running sensor: phase + k·period·(1 + drift), k = 0 … count − 1.
std::vector<double> FreeRunningSampleTimes(const LoggingModel& model, size_t count);

// One written sensor record: which sample (index into the true sample times) and its stamp.
struct LoggedSample {
  size_t sample = 0;
  double stamp_s = 0.0;
};

// The records the logger writes from samples taken at `sample_times_s` (increasing), before
// repeats. Jitter draws are clamped to ±0.45 of the period (logger) or of the shortest sample
// interval (no logger), so the stamps increase.
std::vector<LoggedSample> LogSamples(const LoggingModel& model,
                                     const std::vector<double>& sample_times_s, Random* random);

// One encoder poll: its true time and its stamp.
struct EncoderPoll {
  double true_s = 0.0;
  double stamp_s = 0.0;
};

// Polls covering [begin_s, end_s] (one period beyond each end), model.encoder_period_s > 0.
// Each jitter draw is clamped to ±0.24 period, so the stamps increase.
std::vector<EncoderPoll> EncoderPolls(const LoggingModel& model, double begin_s, double end_s,
                                      Random* random);

// Stamp scatter on polls taken at given true times (encoder_period_s = 0), each draw clamped to
// ±0.24 of the shortest gap between the times.
std::vector<EncoderPoll> StampedPolls(const LoggingModel& model,
                                      const std::vector<double>& true_times_s, Random* random);

// The rows to write: 0 … count − 1 in order, each repeated (written twice in a row) with
// probability `fraction`.
std::vector<size_t> RowsWithRepeats(size_t count, double fraction, Random* random);

}  // namespace calib

#endif  // CALIB_CORE_TIMING_LOGGING_MODEL_H_
