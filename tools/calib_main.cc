// calib: offline calibration of a differential-drive robot from its own logs. Dispatches to the
// commands in tools/commands/; the flags are parsed once, in tools/commands/flags.cc.
#include <calib/tools/commands/commands.h>
#include <calib/tools/commands/flags.h>
#include <calib/tools/commands/help.h>
#include <calib/tools/process_memory.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

constexpr char kUsage[] =
    "calib <command> [flags]\n"
    "  calibrate --input PATH --output OUT.json   estimate the calibration\n"
    "  diagnose  --input PATH --output OUT.json   find physics the model leaves out\n"
    "  simulate  --output LOG [--truth T.json]    write a simulated laser log (.tuple, .csv, or a\n"
    "            raw stream directory when LOG has no extension or with --format stream)\n";

int RunCommand(int argc, char** argv) {
  int exit_code = 0;
  if (calib::cli::HandleHelpOrVersion(argc, argv, kUsage, &exit_code)) return exit_code;
  calib::cli::ParseFlags(kUsage, &argc, &argv);
  if (argc != 2) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const std::string command = argv[1];
  if (command == "calibrate")
    return calib::cli::RunCalibrate(calib::cli::CalibrateOptionsFromFlags());
  if (command == "diagnose") return calib::cli::RunDiagnose(calib::cli::DiagnoseOptionsFromFlags());
  if (command == "simulate") return calib::cli::RunSimulate(calib::cli::SimulateOptionsFromFlags());
  std::fprintf(stderr, "calib: unknown command '%s'\n%s", command.c_str(), kUsage);
  return 2;
}

}  // namespace

// Whatever a command printed on stdout (a summary, the JSON, the help) must have arrived: a full
// disk or a closed pipe behind stdout is an error, not exit 0.
int main(int argc, char** argv) {
  calib::KeepFreedMemory();
  const int exit_code = RunCommand(argc, argv);
  errno = 0;
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    std::fprintf(stderr, "calib: error: cannot write to standard output%s%s\n",
                 errno != 0 ? ": " : "", errno != 0 ? std::strerror(errno) : "");
    return exit_code != 0 ? exit_code : 1;
  }
  // Everything is written: the process ends here, without the destructors of the static objects
  // (freeing that the exit does at once). Under AddressSanitizer the normal return, so that its
  // leak check at exit runs.
#if defined(__SANITIZE_ADDRESS__)
  return exit_code;
#else
  std::_Exit(exit_code);
#endif
}
