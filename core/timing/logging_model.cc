#include <calib/core/text_number.h>
#include <calib/core/timing/logging_model.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace calib {
namespace {

// A normal draw σ·N(0, 1) clamped to ±limit.
double ClampedNormal(double sigma, double limit, Random* random) {
  if (sigma <= 0.0) return 0.0;
  return std::clamp(sigma * random->Normal(), -limit, limit);
}

double ShortestGap(const std::vector<double>& times) {
  double gap = std::numeric_limits<double>::infinity();
  for (size_t k = 1; k < times.size(); ++k) gap = std::min(gap, times[k] - times[k - 1]);
  return gap;
}

// Largest σ of a jitter relative to its period: the clamps cut at ~3σ, rarely.
constexpr double kLoggerJitterShare = 0.15;   // Clamp ±0.45 P.
constexpr double kEncoderJitterShare = 0.08;  // Clamp ±0.24 P for each of poll and stamp.

}  // namespace

bool LoggingModel::IsClean() const {
  return sensor_period_s == 0.0 && sensor_phase_s == 0.0 && sensor_clock_drift == 0.0 &&
         logger_period_s == 0.0 && logger_jitter_s == 0.0 && pickup_latency_s == 0.0 &&
         encoder_period_s == 0.0 && encoder_poll_jitter_s == 0.0 && encoder_stamp_jitter_s == 0.0 &&
         repeat_fraction == 0.0;
}

Status ValidateLoggingModel(const LoggingModel& m) {
  const struct {
    const char* name;
    double value;
  } fields[] = {{"sensor_period_s", m.sensor_period_s},
                {"sensor_phase_s", m.sensor_phase_s},
                {"logger_period_s", m.logger_period_s},
                {"logger_jitter_s", m.logger_jitter_s},
                {"pickup_latency_s", m.pickup_latency_s},
                {"encoder_period_s", m.encoder_period_s},
                {"encoder_poll_jitter_s", m.encoder_poll_jitter_s},
                {"encoder_stamp_jitter_s", m.encoder_stamp_jitter_s},
                {"repeat_fraction", m.repeat_fraction}};
  for (const auto& field : fields) {
    if (!std::isfinite(field.value) || field.value < 0.0) {
      return Status::InvalidInput(std::string("logging model: ") + field.name +
                                  " must be a finite number >= 0, got " + Num(field.value));
    }
  }
  if (!std::isfinite(m.sensor_clock_drift) || std::abs(m.sensor_clock_drift) >= 0.01) {
    return Status::InvalidInput(
        "logging model: sensor_clock_drift must be a relative rate error below 0.01 in size, "
        "got " +
        Num(m.sensor_clock_drift));
  }
  if (m.sensor_period_s == 0.0 && (m.sensor_phase_s != 0.0 || m.sensor_clock_drift != 0.0)) {
    return Status::InvalidInput(
        "logging model: sensor_phase_s and sensor_clock_drift need a free-running sensor "
        "(sensor_period_s > 0)");
  }
  if (m.logger_period_s > 0.0 && m.logger_jitter_s > kLoggerJitterShare * m.logger_period_s) {
    return Status::InvalidInput("logging model: logger_jitter_s (" + Num(m.logger_jitter_s) +
                                ") must be at most 0.15 logger_period_s (" +
                                Num(m.logger_period_s) + ") so that pick-ups stay in order");
  }
  if (m.encoder_period_s == 0.0 && m.encoder_poll_jitter_s > 0.0) {
    return Status::InvalidInput(
        "logging model: encoder_poll_jitter_s needs encoder polls of their own "
        "(encoder_period_s > 0)");
  }
  if (m.encoder_period_s > 0.0 && std::max(m.encoder_poll_jitter_s, m.encoder_stamp_jitter_s) >
                                      kEncoderJitterShare * m.encoder_period_s) {
    return Status::InvalidInput(
        "logging model: encoder_poll_jitter_s and encoder_stamp_jitter_s must each be at most "
        "0.08 encoder_period_s (" +
        Num(m.encoder_period_s) + ") so that the stamps stay in order");
  }
  if (m.repeat_fraction >= 0.5) {
    return Status::InvalidInput("logging model: repeat_fraction must be in [0, 0.5), got " +
                                Num(m.repeat_fraction));
  }
  return Status::Ok();
}

std::vector<double> FreeRunningSampleTimes(const LoggingModel& model, size_t count) {
  std::vector<double> times(count);
  const double period = model.sensor_period_s * (1.0 + model.sensor_clock_drift);
  for (size_t k = 0; k < count; ++k) times[k] = model.sensor_phase_s + k * period;
  return times;
}

std::vector<LoggedSample> LogSamples(const LoggingModel& model,
                                     const std::vector<double>& sample_times_s, Random* random) {
  std::vector<LoggedSample> records;
  if (sample_times_s.empty()) return records;
  const double latency = model.pickup_latency_s;
  if (model.logger_period_s <= 0.0) {
    // Every sample written as it arrives, the stamp scattered about its arrival.
    const double limit = 0.45 * ShortestGap(sample_times_s);
    records.reserve(sample_times_s.size());
    for (size_t k = 0; k < sample_times_s.size(); ++k) {
      const double jitter = ClampedNormal(model.logger_jitter_s, limit, random);
      records.push_back(LoggedSample{k, sample_times_s[k] + latency + jitter});
    }
    return records;
  }
  const double period = model.logger_period_s;
  const double limit = 0.45 * period;
  // The logger's phase relative to the sensor is arbitrary: its first pick-up falls anywhere in
  // the period after the first sample can be picked up.
  const double first = sample_times_s.front() + latency + period * random->Uniform();
  const double last = sample_times_s.back() + latency + period;
  size_t next = 0;  // First sample not yet available.
  for (size_t i = 0;; ++i) {
    const double nominal = first + static_cast<double>(i) * period;
    if (nominal > last) break;
    const double pickup = nominal + ClampedNormal(model.logger_jitter_s, limit, random);
    while (next < sample_times_s.size() && sample_times_s[next] + latency <= pickup) ++next;
    if (next == 0) continue;  // Nothing to pick up yet.
    records.push_back(LoggedSample{next - 1, pickup});
  }
  return records;
}

std::vector<EncoderPoll> EncoderPolls(const LoggingModel& model, double begin_s, double end_s,
                                      Random* random) {
  std::vector<EncoderPoll> polls;
  const double period = model.encoder_period_s;
  if (!(period > 0.0) || !(end_s >= begin_s)) return polls;
  const double limit = 0.24 * period;
  const double first = (std::floor(begin_s / period) - 1.0) * period;
  const size_t count = static_cast<size_t>(std::ceil((end_s - first) / period)) + 2;
  polls.reserve(count);
  for (size_t j = 0; j < count; ++j) {
    EncoderPoll poll;
    poll.true_s = first + static_cast<double>(j) * period +
                  ClampedNormal(model.encoder_poll_jitter_s, limit, random);
    poll.stamp_s = poll.true_s + ClampedNormal(model.encoder_stamp_jitter_s, limit, random);
    polls.push_back(poll);
  }
  return polls;
}

std::vector<EncoderPoll> StampedPolls(const LoggingModel& model,
                                      const std::vector<double>& true_times_s, Random* random) {
  const double limit = 0.24 * ShortestGap(true_times_s);
  std::vector<EncoderPoll> polls(true_times_s.size());
  for (size_t j = 0; j < true_times_s.size(); ++j) {
    polls[j].true_s = true_times_s[j];
    polls[j].stamp_s = true_times_s[j] + ClampedNormal(model.encoder_stamp_jitter_s, limit, random);
  }
  return polls;
}

std::vector<size_t> RowsWithRepeats(size_t count, double fraction, Random* random) {
  std::vector<size_t> rows;
  rows.reserve(count);
  for (size_t k = 0; k < count; ++k) {
    rows.push_back(k);
    if (fraction > 0.0 && random->Uniform() < fraction) rows.push_back(k);
  }
  return rows;
}

}  // namespace calib
