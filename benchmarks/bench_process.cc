#include "benchmarks/bench_process.h"

#include <calib/core/text_format.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

extern char** environ;

namespace calib::bench {
namespace {

namespace fs = std::filesystem;

int64_t FileBytes(const std::string& path) {
  std::error_code error;
  const auto size = fs::file_size(path, error);
  return error ? 0 : static_cast<int64_t>(size);
}

// Without terminal colour codes (ESC [ ... letter).
std::string StripEscapes(const std::string& text) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\x1b' && i + 1 < text.size() && text[i + 1] == '[') {
      i += 2;
      while (i < text.size() && !std::isalpha(static_cast<unsigned char>(text[i]))) ++i;
      continue;
    }
    if (text[i] != '\r') out += text[i];
  }
  return out;
}

// The last line of the file with anything visible on it.
std::string LastLine(const std::string& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line)) {
    line = StripEscapes(line);
    if (line.find_first_not_of(" \t") != std::string::npos) last = line;
  }
  return last.size() > 200 ? last.substr(0, 200) + "…" : last;
}

long StatusFieldKb(const char* path, const char* field) {
  std::ifstream in(path);
  std::string line;
  const std::string prefix = std::string(field) + ":";
  while (std::getline(in, line)) {
    if (line.rfind(prefix, 0) == 0) return std::stol(line.substr(prefix.size()));
  }
  return -1;
}

std::vector<char*> CArgs(const std::vector<std::string>& args) {
  std::vector<char*> c_args;
  for (const std::string& arg : args) c_args.push_back(const_cast<char*>(arg.c_str()));
  c_args.push_back(nullptr);
  return c_args;
}

// In the forked child: cwd, stdout/stderr to files, then exec; errno goes back through
// `error_fd` (closed on a successful exec).
// The limits a measured program runs under. Stack: at least 256 MiB (the authors' solver keeps
// 3N doubles in a stack array, 24 MB at N = 10⁶, beyond the usual 8 MB; glibc sizes thread
// stacks by it too, in address space only). Address space: 90 % of MemAvailable, so that a
// program too large for the machine fails alone instead of waking the OOM killer. Either limit
// is 0 when left as it was.
struct ChildLimits {
  rlim_t stack_bytes = 0;
  rlim_t address_space_bytes = 0;
};

ChildLimits PlanLimits() {
  ChildLimits limits;
  rlimit stack{};
  if (getrlimit(RLIMIT_STACK, &stack) == 0) {
    limits.stack_bytes = std::min<rlim_t>(stack.rlim_max, rlim_t{256} << 20);
  }
  const long available_kb = StatusFieldKb("/proc/meminfo", "MemAvailable");
  if (available_kb > 0)
    limits.address_space_bytes = static_cast<rlim_t>(available_kb) * 1024 / 10 * 9;
  return limits;
}

void ApplyLimits(const ChildLimits& limits) {
  rlimit limit{};
  if (limits.stack_bytes > 0 && getrlimit(RLIMIT_STACK, &limit) == 0) {
    limit.rlim_cur = std::max(limit.rlim_cur, limits.stack_bytes);
    setrlimit(RLIMIT_STACK, &limit);
  }
  if (limits.address_space_bytes > 0 && getrlimit(RLIMIT_AS, &limit) == 0) {
    limit.rlim_cur = std::min(limit.rlim_max, limits.address_space_bytes);
    setrlimit(RLIMIT_AS, &limit);
  }
}

[[noreturn]] void ExecInChild(const std::vector<char*>& args, const std::string& dir,
                              const ChildLimits& limits, int error_fd) {
  ApplyLimits(limits);
  int err = 0;
  if (chdir(dir.c_str()) != 0) err = errno;
  const int out = open((dir + "/stdout.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const int errf = open((dir + "/stderr.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (err == 0 && (out < 0 || errf < 0)) err = errno;
  if (err == 0) {
    dup2(out, STDOUT_FILENO);
    dup2(errf, STDERR_FILENO);
    const int null_in = open("/dev/null", O_RDONLY);
    if (null_in >= 0) dup2(null_in, STDIN_FILENO);
    execv(args[0], args.data());
    err = errno;
  }
  (void)!write(error_fd, &err, sizeof(err));
  _exit(127);
}

}  // namespace

nlohmann::json ToJson(const ProcessRun& run) {
  nlohmann::json j = {{"exit_code", run.exit_code},
                      {"signal", run.signal},
                      {"wall_s", run.wall_s},
                      {"cpu_s", run.cpu_s},
                      {"maxrss_kb", run.maxrss_kb},
                      {"minflt", run.minflt},
                      {"majflt", run.majflt},
                      {"output_bytes", run.output_bytes},
                      {"launcher_rss_kb", run.launcher_rss_kb},
                      {"stack_limit_mb", run.stack_limit_mb},
                      {"address_space_limit_mb", run.address_space_limit_mb}};
  if (!run.error.empty()) j["error"] = run.error;
  if (!run.stderr_tail.empty()) j["stderr_tail"] = run.stderr_tail;
  return j;
}

ProcessRun ProcessRunFromJson(const nlohmann::json& j) {
  ProcessRun run;
  run.error = j.value("error", "");
  run.exit_code = j.value("exit_code", -1);
  run.signal = j.value("signal", 0);
  run.wall_s = j.value("wall_s", 0.0);
  run.cpu_s = j.value("cpu_s", 0.0);
  run.maxrss_kb = j.value("maxrss_kb", 0L);
  run.minflt = j.value("minflt", 0L);
  run.majflt = j.value("majflt", 0L);
  run.output_bytes = j.value("output_bytes", int64_t{0});
  run.launcher_rss_kb = j.value("launcher_rss_kb", 0L);
  run.stderr_tail = j.value("stderr_tail", "");
  run.stack_limit_mb = j.value("stack_limit_mb", 0.0);
  run.address_space_limit_mb = j.value("address_space_limit_mb", 0.0);
  return run;
}

std::vector<std::string> ExpandArgs(const std::string& pattern,
                                    const std::map<std::string, std::string>& values) {
  std::vector<std::string> args;
  std::istringstream words(pattern);
  std::string word;
  while (words >> word) {
    for (const auto& [key, value] : values) {
      const std::string placeholder = "{" + key + "}";
      for (size_t at = word.find(placeholder); at != std::string::npos;
           at = word.find(placeholder, at + value.size())) {
        word.replace(at, placeholder.size(), value);
      }
    }
    args.push_back(word);
  }
  return args;
}

ProcessRun RunAndMeasure(const std::vector<std::string>& argv, const std::string& dir,
                         const std::string& output_file) {
  ProcessRun run;
  run.launcher_rss_kb = StatusFieldKb("/proc/self/status", "VmRSS");
  if (argv.empty()) {
    run.error = "empty command";
    return run;
  }
  if (!output_file.empty()) fs::remove(output_file);
  const std::vector<char*> args = CArgs(argv);
  const ChildLimits limits = PlanLimits();
  run.stack_limit_mb = static_cast<double>(limits.stack_bytes) / 1048576;
  run.address_space_limit_mb = static_cast<double>(limits.address_space_bytes) / 1048576;
  int error_pipe[2];
  if (pipe2(error_pipe, O_CLOEXEC) != 0) {
    run.error = std::string("pipe: ") + std::strerror(errno);
    return run;
  }
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) ExecInChild(args, dir, limits, error_pipe[1]);
  close(error_pipe[1]);
  if (pid < 0) {
    close(error_pipe[0]);
    run.error = std::string("fork: ") + std::strerror(errno);
    return run;
  }
  int exec_errno = 0;
  const bool exec_failed = read(error_pipe[0], &exec_errno, sizeof(exec_errno)) > 0;
  close(error_pipe[0]);
  int status = 0;
  rusage usage{};
  while (wait4(pid, &status, 0, &usage) < 0 && errno == EINTR) {
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.cpu_s = usage.ru_utime.tv_sec + usage.ru_utime.tv_usec * 1e-6 + usage.ru_stime.tv_sec +
              usage.ru_stime.tv_usec * 1e-6;
  run.maxrss_kb = usage.ru_maxrss;
  run.minflt = usage.ru_minflt;
  run.majflt = usage.ru_majflt;
  if (WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) run.signal = WTERMSIG(status);
  run.output_bytes = FileBytes(dir + "/stdout.txt");
  if (!output_file.empty()) run.output_bytes += FileBytes(output_file);
  run.stderr_tail = LastLine(dir + "/stderr.txt");
  if (exec_failed) {
    run.error = "cannot run " + argv[0] + ": " + std::strerror(exec_errno);
  } else if (run.signal != 0) {
    run.error = "killed by signal " + std::to_string(run.signal) + " (" + strsignal(run.signal) +
                Format("; limits: stack %.0f MB, address space %.0f MB)", run.stack_limit_mb,
                       run.address_space_limit_mb);
  } else if (run.exit_code != 0) {
    run.error = "exit code " + std::to_string(run.exit_code) +
                Format(" (address space limited to %.0f MB)", run.address_space_limit_mb);
  } else if (run.output_bytes == 0) {
    run.error = "printed nothing (no stdout, no output file)";
  }
  return run;
}

ProcessRun RunThroughLauncher(const std::string& self, const std::vector<std::string>& argv,
                              const std::string& dir, const std::string& output_file) {
  const std::string result = dir + "/launcher_result.json";
  fs::remove(result);
  std::vector<std::string> launcher = {self, "--measure_child", result, dir, output_file};
  launcher.insert(launcher.end(), argv.begin(), argv.end());
  const std::vector<char*> args = CArgs(launcher);
  // posix_spawn does not copy this (possibly large) process's page tables.
  pid_t pid = 0;
  ProcessRun run;
  if (posix_spawn(&pid, self.c_str(), nullptr, nullptr, args.data(), environ) != 0) {
    run.error = "cannot start the launcher " + self;
    return run;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(result), nullptr, false);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || j.is_discarded()) {
    run.error = "the launcher failed (status " + std::to_string(status) + ")";
    return run;
  }
  return ProcessRunFromJson(j);
}

int RunLauncherMain(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: %s --measure_child RESULT.json DIR OUTPUT_FILE PROG [ARGS...]\n",
                 argv[0]);
    return 2;
  }
  const std::vector<std::string> command(argv + 5, argv + argc);
  const ProcessRun run = RunAndMeasure(command, argv[3], argv[4]);
  std::ofstream out(argv[2]);
  out << ToJson(run).dump() << "\n";
  return out.good() ? 0 : 1;
}

StatusOr<nlohmann::json> RunJsonChild(const std::string& command) {
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return Status::Io("cannot run " + command);
  std::string last, line;
  char buffer[4096];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) {
    line += buffer;
    if (line.back() != '\n') continue;
    if (line[0] == '{') last = line;
    line.clear();
  }
  const int status = pclose(pipe);
  if (status != 0 || last.empty()) {
    return Status::Internal("child failed (status " + std::to_string(status) + "): " + command);
  }
  const nlohmann::json j = nlohmann::json::parse(last, nullptr, false);
  if (j.is_discarded()) return Status::Internal("child printed bad JSON: " + last);
  return j;
}

long MemAvailableKb() { return StatusFieldKb("/proc/meminfo", "MemAvailable"); }

long SelfRssKb() { return StatusFieldKb("/proc/self/status", "VmRSS"); }

}  // namespace calib::bench
