#ifndef CALIB_TOOLS_COMMANDS_HELP_H_
#define CALIB_TOOLS_COMMANDS_HELP_H_

// `calib -h`, `calib --help`, `calib help [COMMAND]`, `calib COMMAND --help` and
// `calib --version`, answered before the flags are parsed (gflags' own --help lists every flag of
// every library; a command's help lists that command's flags only).
namespace calib::cli {

// True when argv asks for help or the version: the answer is printed on stdout and *exit_code
// is set (0).
bool HandleHelpOrVersion(int argc, char** argv, const char* usage, int* exit_code);

}  // namespace calib::cli

#endif  // CALIB_TOOLS_COMMANDS_HELP_H_
