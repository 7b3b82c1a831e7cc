#include <calib/tools/commands/help.h>
#include <gflags/gflags.h>

#include <cstdio>
#include <string>
#include <vector>

#ifndef CALIB_VERSION
#define CALIB_VERSION "unknown"
#endif

namespace calib::cli {
namespace {

constexpr const char* kCommands[] = {"calibrate", "diagnose", "simulate"};

bool IsHelpWord(const std::string& arg) {
  return arg == "-h" || arg == "--help" || arg == "-help" || arg == "help" || arg == "--h";
}

bool IsVersionWord(const std::string& arg) {
  return arg == "--version" || arg == "-version" || arg == "version";
}

std::string CommandIn(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    for (const char* command : kCommands) {
      if (argv[i] == std::string(command)) return command;
    }
  }
  return "";
}

// The flags of tools/commands/flags.cc that a command reads: a description starting with
// "COMMAND:" belongs to that command; one without such a prefix is shared by calibrate and
// diagnose (diagnose runs a calibration first); `output` also serves simulate.
bool FlagBelongsTo(const gflags::CommandLineFlagInfo& flag, const std::string& command) {
  const std::string& text = flag.description;
  // "simulate: ..." or "simulate (streams): ...".
  for (const char* other : kCommands) {
    const std::string name = other;
    if (text.compare(0, name.size(), name) == 0 && text.size() > name.size() &&
        (text[name.size()] == ':' || text[name.size()] == ' ')) {
      return command == other;
    }
  }
  if (command == "simulate") return flag.name == "output" || flag.name == "time_offset";
  return true;
}

void PrintCommandFlags(const std::string& command) {
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  std::printf("calib %s [flags]\n\nFlags:\n", command.c_str());
  for (const gflags::CommandLineFlagInfo& flag : flags) {
    const std::string& file = flag.filename;
    const std::string ours = "commands/flags.cc";
    if (file.size() < ours.size() || file.compare(file.size() - ours.size(), ours.size(), ours))
      continue;
    if (!FlagBelongsTo(flag, command)) continue;
    std::string text = flag.description;
    const std::string prefix = command + ": ";
    if (text.compare(0, prefix.size(), prefix) == 0) text.erase(0, prefix.size());
    const std::string fallback =
        flag.type == "string" ? "\"" + flag.default_value + "\"" : flag.default_value;
    std::printf("  --%s (default %s)\n      %s\n", flag.name.c_str(), fallback.c_str(),
                text.c_str());
  }
}

}  // namespace

bool HandleHelpOrVersion(int argc, char** argv, const char* usage, int* exit_code) {
  bool help = false;
  bool version = false;
  for (int i = 1; i < argc; ++i) {
    help = help || IsHelpWord(argv[i]);
    version = version || IsVersionWord(argv[i]);
  }
  if (!help && !version) return false;
  *exit_code = 0;
  if (version && !help) {
    std::printf("calib %s\n", CALIB_VERSION);
    return true;
  }
  const std::string command = CommandIn(argc, argv);
  if (command.empty()) {
    std::printf(
        "%s\n`calib COMMAND --help` lists a command's flags; `calib --version` prints "
        "the version.\n",
        usage);
  } else {
    PrintCommandFlags(command);
  }
  return true;
}

}  // namespace calib::cli
