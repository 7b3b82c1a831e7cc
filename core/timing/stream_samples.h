#ifndef CALIB_CORE_TIMING_STREAM_SAMPLES_H_
#define CALIB_CORE_TIMING_STREAM_SAMPLES_H_

#include <calib/core/encoder_sample.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/se2.h>
#include <calib/core/status.h>

#include <string>
#include <vector>

// Raw laser streams prepared for a calibration with latent sample times: stamps relative to one
// origin (so that times stay precise as Jets), held repeats dropped, each sensor sample bracketed
// by the encoder samples around its stamp, and the usable intervals.
namespace calib {

struct StreamSample {
  double stamp_s = 0.0;  // Relative to StreamSamples::origin_s.
  Pose2d world_T_sensor = Pose2d::Zero();
  int record = 0;   // 1-based position in the input stream.
  int line = 0;     // Its line in sensor_poses.csv (0: not from a file).
  int bracket = 0;  // Last encoder sample with stamp ≤ this stamp (the next one is after it).
  int segment = 0;  // StampedPose::segment: no interval joins two segments.
};

struct StreamSamples {
  double origin_s = 0.0;                // The first encoder stamp, subtracted from every stamp.
  std::vector<EncoderSample> encoders;  // Stamps relative to origin_s.
  std::vector<StreamSample> samples;    // Distinct sensor samples inside the encoder span.
  std::vector<int> interval_start;      // k: (samples[k], samples[k + 1]) is an interval.
  int held_repeats_dropped = 0;         // Sensor records repeating the previous one's values.
  // The stamps (relative to origin_s) of the held repeats of samples that were kept: a logger
  // picked that sample up again.
  std::vector<double> held_stamp_s;
  int exact_duplicates_dropped = 0;  // Records repeating the previous one's stamp and values.
  int outside_encoder_span = 0;      // Sensor samples stamped before or after every encoder.
  double outside_by_s = 0.0;         // The farthest of them from the span (s).
  double encoder_period_s = 0.0;     // Median stamp step.
  double sensor_period_s = 0.0;      // Median stamp step of the distinct samples.
};

// Fails (InvalidInput, naming `source`, the stream and the record) on too few samples, non-finite
// values, stamps that go back, a repeated stamp with different values, or no usable interval.
// Intervals over an encoder gap (a step above 5x the median encoder period) are left out.
StatusOr<StreamSamples> BuildStreamSamples(const std::vector<EncoderSample>& odometry,
                                           const std::vector<StampedPose>& sensor_poses,
                                           const std::string& source);

}  // namespace calib

#endif  // CALIB_CORE_TIMING_STREAM_SAMPLES_H_
