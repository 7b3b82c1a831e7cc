#include <calib/core/text_number.h>
#include <calib/core/timing/sample_clock.h>
#include <calib/core/timing/stream_samples.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace calib {
namespace {

std::string Record(const std::string& stream, size_t k) {
  return stream + " record " + std::to_string(k + 1) + ": ";
}

StatusOr<std::vector<EncoderSample>> DistinctEncoders(const std::vector<EncoderSample>& odometry,
                                                      const std::string& stream, int* dropped) {
  std::vector<EncoderSample> kept;
  for (size_t k = 0; k < odometry.size(); ++k) {
    const EncoderSample& s = odometry[k];
    if (!std::isfinite(s.t_s) || !std::isfinite(s.left_rad) || !std::isfinite(s.right_rad)) {
      return Status::InvalidInput(Record(stream, k) + "values must be finite");
    }
    if (!kept.empty() && s.t_s == kept.back().t_s) {
      if (s.left_rad == kept.back().left_rad && s.right_rad == kept.back().right_rad) {
        ++*dropped;
        continue;
      }
      return Status::InvalidInput(Record(stream, k) + "repeats the stamp t=" + Num(s.t_s) +
                                  " of the record before it with different values");
    }
    if (!kept.empty() && s.t_s < kept.back().t_s) {
      return Status::InvalidInput(Record(stream, k) + "stamp t=" + Num(s.t_s) + " goes back from " +
                                  Num(kept.back().t_s));
    }
    kept.push_back(s);
  }
  if (kept.size() < 2) return Status::InvalidInput(stream + ": needs at least 2 samples");
  return kept;
}

Status AddSensorSamples(const std::vector<StampedPose>& poses, const std::string& stream,
                        StreamSamples* out) {
  const std::vector<EncoderSample>& enc = out->encoders;
  const Pose2d* last = nullptr;
  double last_stamp = -INFINITY;
  bool last_kept = false;
  for (size_t k = 0; k < poses.size(); ++k) {
    const StampedPose& p = poses[k];
    if (!std::isfinite(p.t_s) || !p.world_T_sensor.allFinite()) {
      return Status::InvalidInput(Record(stream, k) + "values must be finite");
    }
    const bool same_values = last != nullptr && p.world_T_sensor == *last;
    if (p.t_s == last_stamp && !same_values) {
      return Status::InvalidInput(Record(stream, k) + "repeats the stamp t=" + Num(p.t_s) +
                                  " of the record before it with different values");
    }
    if (p.t_s < last_stamp) {
      return Status::InvalidInput(Record(stream, k) + "stamp t=" + Num(p.t_s) + " goes back from " +
                                  Num(last_stamp));
    }
    if (same_values) {
      // The logger picked up the same sample again: it was taken before the first pick-up.
      if (p.t_s == last_stamp) {
        ++out->exact_duplicates_dropped;
      } else {
        ++out->held_repeats_dropped;
        if (last_kept) out->held_stamp_s.push_back(p.t_s - out->origin_s);
      }
      continue;
    }
    last = &p.world_T_sensor;
    last_stamp = p.t_s;
    const double stamp = p.t_s - out->origin_s;
    auto after = std::upper_bound(enc.begin(), enc.end(), stamp,
                                  [](double t, const EncoderSample& s) { return t < s.t_s; });
    // A sample stamped with the last encoder lies in the last bracket, not outside the span.
    if (after == enc.end() && enc.size() >= 2 && stamp == enc.back().t_s) --after;
    last_kept = after != enc.begin() && after != enc.end();
    if (!last_kept) {  // Outside the encoder span.
      ++out->outside_encoder_span;
      const double by = std::max(enc.front().t_s - stamp, stamp - enc.back().t_s);
      out->outside_by_s = std::max(out->outside_by_s, by);
      continue;
    }
    out->samples.push_back(StreamSample{stamp, p.world_T_sensor, static_cast<int>(k) + 1, p.line,
                                        static_cast<int>(after - enc.begin()) - 1, p.segment});
  }
  return Status::Ok();
}

}  // namespace

StatusOr<StreamSamples> BuildStreamSamples(const std::vector<EncoderSample>& odometry,
                                           const std::vector<StampedPose>& sensor_poses,
                                           const std::string& source) {
  StreamSamples out;
  CALIB_ASSIGN_OR_RETURN(out.encoders, DistinctEncoders(odometry, source + " (odometry)",
                                                        &out.exact_duplicates_dropped));
  out.origin_s = out.encoders.front().t_s;
  std::vector<double> encoder_stamps;
  for (EncoderSample& s : out.encoders) {
    s.t_s -= out.origin_s;
    encoder_stamps.push_back(s.t_s);
  }
  out.encoder_period_s = MedianStep(encoder_stamps);
  CALIB_RETURN_IF_ERROR(AddSensorSamples(sensor_poses, source + " (sensor poses)", &out));
  if (out.samples.size() < 2) {
    return Status::InvalidInput(
        source + " (sensor poses): " + std::to_string(out.samples.size()) +
        " distinct sample(s) inside the encoders' time span (" +
        std::to_string(out.held_repeats_dropped) + " rows repeat the values before them, " +
        std::to_string(out.outside_encoder_span) + " lie outside the span); needs at least 2");
  }
  std::vector<double> stamps;
  for (const StreamSample& s : out.samples) stamps.push_back(s.stamp_s);
  out.sensor_period_s = MedianStep(stamps);
  const double gap = 5.0 * out.encoder_period_s;
  for (size_t k = 0; k + 1 < out.samples.size(); ++k) {
    bool usable = out.samples[k].segment == out.samples[k + 1].segment;
    for (int j = out.samples[k].bracket; j <= out.samples[k + 1].bracket && usable; ++j) {
      usable = out.encoders[j + 1].t_s - out.encoders[j].t_s <= gap;
    }
    if (usable) out.interval_start.push_back(static_cast<int>(k));
  }
  if (out.interval_start.empty()) {
    return Status::InvalidInput(source +
                                ": no pair of sensor samples lies inside the encoder span "
                                "without an encoder gap or a break of the sensor's pose chain");
  }
  return out;
}

}  // namespace calib
