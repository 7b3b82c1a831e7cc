#ifndef CALIB_CORE_BEARING_BEARING_LOG_IO_H_
#define CALIB_CORE_BEARING_BEARING_LOG_IO_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/status.h>

#include <string>
#include <string_view>
#include <vector>

// Reader and writer for bearing logs (CONTRACT.md): a directory with odometry.csv
// (run,t,left,right), bearings.csv (run,t,bearing) and meta.json. Every error message names the
// file, the line where there is one, and what is wrong.
namespace calib {

// Reads and validates a log directory: ReadBearingLog = the three parsers + ValidateBearingLog;
// the log's stream_timing holds {odometry, bearings}.
StatusOr<BearingLog> ReadBearingLog(const std::string& directory);
// The same over the three files' text, named in messages as if read from `directory`.
StatusOr<BearingLog> ParseBearingLog(std::string_view odometry_csv, std::string_view bearings_csv,
                                     std::string_view meta_json, const std::string& directory);

// Parsers over in-memory text; `source` is the file name used in messages. CSV: a header naming
// the columns (any order, extra columns ignored), then one sample per line; blank lines and lines
// starting with '#' are skipped. Runs come back sorted by id, samples in file order. Within a
// run, exact duplicate records (same t, same values) are dropped; a repeated t with different
// values is an error naming both lines. `timing` (may be null) receives the stream's timing
// diagnostics, each run analysed on its own and pooled (PoolStreamTiming).
// Isolated spikes of a run's wheel angles (encoder_spikes.h) are dropped, with a sentence in
// `warnings` (may be null).
StatusOr<std::vector<BearingRun>> ParseBearingOdometryCsv(
    std::string_view text, const std::string& source, StreamTiming* timing = nullptr,
    std::vector<std::string>* warnings = nullptr);
// Adds the bearings to `runs` (from ParseBearingOdometryCsv), checking each against its run;
// duplicates and `timing` as above. A handful of bearings outside (−π, π] or outside their run's
// odometry (at most n/50) are glitches: dropped, with a sentence in `warnings` (may be
// null); more are an error naming the first.
Status ParseBearingsCsv(std::string_view text, const std::string& source,
                        std::vector<BearingRun>* runs, StreamTiming* timing = nullptr,
                        std::vector<std::string>* warnings = nullptr);
StatusOr<BearingLogMeta> ParseBearingMeta(std::string_view text, const std::string& source);

// The invariants every consumer may rely on, for logs built in memory: positive finite nominal
// r and B; per run at least two encoder samples with strictly increasing finite times and finite
// angles, at least one bearing, bearings finite, in (−π, π], strictly increasing in time and
// inside the run's odometry time span; unique run ids in increasing order; an initial distance
// that names an existing run and is positive.
Status ValidateBearingLog(const BearingLog& log);

// Writes the three files (creating the directory), numbers in shortest round-trip form.
Status WriteBearingLog(const BearingLog& log, const std::string& directory);

}  // namespace calib

#endif  // CALIB_CORE_BEARING_BEARING_LOG_IO_H_
