#ifndef CALIB_CORE_BEARING_BEARING_LOG_H_
#define CALIB_CORE_BEARING_BEARING_LOG_H_

#include <calib/core/encoder_sample.h>
#include <calib/core/timing/stamp_timing.h>

#include <optional>
#include <string>
#include <vector>

// A bearing-only calibration log (CONTRACT.md, "Bearing problem (Martinelli)"): runs of wheel
// encoder samples and bearings of a single landmark, plus the nominal odometry of meta.json.
namespace calib {

// Direction of the landmark in the sensor frame, wrapped to (−π, π].
struct BearingSample {
  double t_s = 0.0;
  double bearing_rad = 0.0;
  int line = 0;  // 1-based line in bearings.csv (0: not from a file).
};

// One run: encoder samples in strictly increasing time, bearings inside their time span.
struct BearingRun {
  int id = 0;
  std::vector<EncoderSample> odometry;
  std::vector<BearingSample> bearings;
};

// The robot–landmark distance at the start of a run (its first encoder sample); fixes the scale.
struct InitialDistance {
  int run = 0;
  double meters = 0.0;
};

struct BearingLogMeta {
  double wheel_radius_m = 0.0;  // Nominal r: wheel travel = r × wheel rotation.
  double wheelbase_m = 0.0;     // Nominal B.
  std::optional<InitialDistance> initial_distance;
};

struct BearingLog {
  std::string source;  // Directory (or other origin), for messages.
  BearingLogMeta meta;
  std::vector<BearingRun> runs;  // Sorted by id.
  // What the reader dropped on the way (glitches), one sentence each.
  std::vector<std::string> warnings;
  // Timing diagnostics filled by ReadBearingLog: "odometry" then "bearings", each pooled over
  // the runs (every run analysed on its own clock; see PoolStreamTiming). Empty when built in
  // memory.
  std::vector<StreamTiming> stream_timing;
};

}  // namespace calib

#endif  // CALIB_CORE_BEARING_BEARING_LOG_H_
