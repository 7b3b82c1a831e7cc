#ifndef CALIB_TOOLS_COMMANDS_FLAGS_H_
#define CALIB_TOOLS_COMMANDS_FLAGS_H_

#include <calib/tools/commands/commands.h>

// The command line's flags (gflags), defined and read only in flags.cc.
namespace calib::cli {

// Parses and removes the flags from argc/argv; `usage` heads --help.
void ParseFlags(const char* usage, int* argc, char*** argv);

CalibrateOptions CalibrateOptionsFromFlags();
DiagnoseOptions DiagnoseOptionsFromFlags();
SimulateOptions SimulateOptionsFromFlags();

}  // namespace calib::cli

#endif  // CALIB_TOOLS_COMMANDS_FLAGS_H_
