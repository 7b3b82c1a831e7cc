#ifndef CALIB_CORE_LASER_LASER_LOG_IO_H_
#define CALIB_CORE_LASER_LASER_LOG_IO_H_

#include <calib/core/encoder_sample.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/se2.h>
#include <calib/core/status.h>
#include <calib/core/text_file.h>

#include <string>
#include <string_view>
#include <vector>

// Readers and writers for laser–odometry logs (formats in CONTRACT.md). Every error message names
// the file, the line (and record where there is one) and what is wrong.
namespace calib {

enum class LaserFormat {
  kAuto,    // Detected from content: '{' first → tuples; a directory → stream; else CSV.
  kTuples,  // Published JSON tuples {"T","phi_l","phi_r","sm":[x,y,theta]}, any white space.
  kCsv,     // Header naming at least T,phi_l,phi_r,sm_x,sm_y,sm_theta (any order), optional t.
  kStream,  // Directory with odometry.csv (t,left,right) and sensor_poses.csv (t,x,y,theta).
};

// "auto", "tuples" (or "json"), "csv", "stream".
StatusOr<LaserFormat> ParseLaserFormat(const std::string& name);

StatusOr<LaserLog> ReadLaserLog(const std::string& path, LaserFormat format = LaserFormat::kAuto);

// Parsers over in-memory text; `source` is the name used in messages. Records (a CSV line, a
// tuple) longer than kMaxLineBytes and headers of more than kMaxCsvColumns columns are errors;
// an allocation failure is an error naming `source`. `release`, when given, is told as the parse
// moves on which bytes it will not read again (MappedFile::Releaser).
StatusOr<LaserLog> ParseLaserTuples(std::string_view text, const std::string& source,
                                    const ReleaseText& release = {});
StatusOr<LaserLog> ParseLaserCsv(std::string_view text, const std::string& source,
                                 const ReleaseText& release = {});
// What ReadLaserLog does with a file's text (tuples or CSV; kAuto detects, kStream is an error):
// the parse, then intervals holding a value no unit explains dropped with a warning.
StatusOr<LaserLog> ParseLaserLog(std::string_view text, const std::string& source,
                                 LaserFormat format = LaserFormat::kAuto,
                                 const ReleaseText& release = {});

// Raw streams: StampedPose and LaserStreams {odometry, sensor_poses} are in laser_log.h.

// One interval per pair of consecutive sensor poses: sm = pose_k⁻¹ ∘ pose_{k+1}; the wheel
// rotations over the interval are integrated from the encoder samples inside it (linear
// interpolation of the cumulative angles at the interval ends), kept as constant-speed steps.
// Intervals that contain an encoder gap (a sample period longer than 5x the median period) are
// dropped and the next kept one is marked gap_before. Poses outside the encoder time span are
// dropped. `steps` is filled only when encoder samples fall strictly inside the interval.
// Exact duplicate samples are dropped (counted in the timing); the log carries the samples in
// `streams` and their timing diagnostics in `stream_timing`.
StatusOr<LaserLog> LaserLogFromStreams(const std::vector<EncoderSample>& odometry,
                                       const std::vector<StampedPose>& sensor_poses,
                                       const std::string& source);
// The same with the two streams' names for messages and diagnostics (a bag's topics).
StatusOr<LaserLog> LaserLogFromStreams(const std::vector<EncoderSample>& odometry,
                                       const std::vector<StampedPose>& sensor_poses,
                                       const std::string& source, const std::string& odometry_name,
                                       const std::string& poses_name);
// Reads odometry.csv and sensor_poses.csv: exact duplicate records (same stamp, same values) are
// dropped and counted; a repeated stamp with different values is an error naming both lines;
// stamps must otherwise increase strictly and values be finite. `timing` (may be null) receives
// one StreamTiming per stream ("odometry", "sensor_poses"). Samples keep their source lines.
StatusOr<LaserStreams> ReadLaserStreamSamples(const std::string& directory,
                                              std::vector<StreamTiming>* timing);
// odometry.csv alone (t,left,right) with its lines; duplicates, order and values are checked
// where the streams are put together (LaserLogFromStreams).
StatusOr<std::vector<EncoderSample>> ReadOdometryCsv(const std::string& path);
// ReadLaserStreamSamples + LaserLogFromStreams; the log carries the streams and their timing.
StatusOr<LaserLog> ReadLaserStream(const std::string& directory);
// The same over the two files' text, named in messages as if read from `directory`.
StatusOr<LaserLog> ParseLaserStream(std::string_view odometry_csv,
                                    std::string_view sensor_poses_csv,
                                    const std::string& directory);
// A raw-stream log whose sensor sample stamped t was taken at t + offset_s (a known latency):
// the sensor poses moved and the intervals built again. An error for a log without raw streams
// (tuples, CSV), whose intervals carry no sample stamps to move.
StatusOr<LaserLog> ShiftSensorStamps(LaserLog log, double offset_s);

// Writers emit the shortest decimal form that reads back bit-exact. They write the interval
// values only: `steps`, `line` and `record` are not stored. WriteLaserTuples adds the key "t"
// when log.has_timestamps, so gaps survive a round trip; the CSV always has the t column.
Status WriteLaserTuples(const LaserLog& log, const std::string& path);
Status WriteLaserCsv(const LaserLog& log, const std::string& path);  // Includes the t column.
Status WriteLaserStream(const std::vector<EncoderSample>& odometry,
                        const std::vector<StampedPose>& sensor_poses, const std::string& directory);

}  // namespace calib

#endif  // CALIB_CORE_LASER_LASER_LOG_IO_H_
