#ifndef CALIB_BENCHMARKS_BENCH_PROCESS_H_
#define CALIB_BENCHMARKS_BENCH_PROCESS_H_

#include <calib/core/status.h>

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// One program run as a child process (fork/exec + wait4), measured from outside: what a user of
// either program pays, start-up included.
namespace calib::bench {

struct ProcessRun {
  std::string error;  // Empty when the program ran, exited 0 and printed something.
  int exit_code = -1;
  int signal = 0;
  double wall_s = 0;
  double cpu_s = 0;  // user + sys
  long maxrss_kb = 0;
  long minflt = 0;
  long majflt = 0;
  int64_t output_bytes = 0;  // stdout plus the {output} file
  // The launcher's RSS at fork: the most ru_maxrss can inherit from it (fork copies only its
  // anonymous pages, so a small program reads far less).
  long launcher_rss_kb = 0;
  double stack_limit_mb = 0;  // The limits it ran under (RunAndMeasure); 0: unchanged.
  double address_space_limit_mb = 0;
  std::string stderr_tail;  // Last line of stderr, for a failure's message.
  bool ok() const { return error.empty(); }
};

nlohmann::json ToJson(const ProcessRun& run);
ProcessRun ProcessRunFromJson(const nlohmann::json& j);

// Splits `pattern` at spaces and replaces "{key}" in each word by values[key].
std::vector<std::string> ExpandArgs(const std::string& pattern,
                                    const std::map<std::string, std::string>& values);

// Runs argv in `dir` (stdout and stderr to files there) and waits for it, with the stack limit
// raised to 256 MiB and the address space limited to 90 % of MemAvailable. `output_file`, when not
// empty, counts as printed output too.
ProcessRun RunAndMeasure(const std::vector<std::string>& argv, const std::string& dir,
                         const std::string& output_file);

// The same through a fresh launcher, `self` re-executed as `self --measure_child ...`: a forked
// child's ru_maxrss starts from its parent's peak (Linux keeps the old image's high-water mark
// across exec), and this bench's own peak is large after simulating a long log.
ProcessRun RunThroughLauncher(const std::string& self, const std::vector<std::string>& argv,
                              const std::string& dir, const std::string& output_file);

// The launcher's side: argv = {self, "--measure_child", RESULT.json, DIR, OUTPUT_FILE, PROG,
// ARGS...}; writes the ProcessRun as JSON and returns 0 (2 on bad arguments).
int RunLauncherMain(int argc, char** argv);

// Runs `command` through the shell and returns the last line of its stdout that starts with '{'.
StatusOr<nlohmann::json> RunJsonChild(const std::string& command);

// Memory the machine can give now (MemAvailable), in kB; -1 when unknown.
long MemAvailableKb();
// This process's resident set now (VmRSS), in kB; -1 when unknown.
long SelfRssKb();

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_PROCESS_H_
