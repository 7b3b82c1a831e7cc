#ifndef CALIB_TOOLS_COMMANDS_PLOT_OUTPUT_H_
#define CALIB_TOOLS_COMMANDS_PLOT_OUTPUT_H_

#include <calib/core/status.h>
#include <calib/tools/commands/commands.h>
#include <calib/tools/report/svg_plot.h>

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// Where the commands' plots go and in which format: SVG always; with --plot_format png also a PNG
// beside each SVG, rasterized by rsvg-convert (Debian package librsvg2-bin).
namespace calib::cli {

// --plot_format is svg or png, and for png the rasterizer is installed.
Status CheckPlotFormat(const std::string& format);

// With format png, converts each SVG of `written` and appends the PNG files.
Status AddRasterized(const std::string& format, std::vector<std::string>* written);

// Writes `files` into `directory` (created) in `format`; returns every file written.
StatusOr<std::vector<std::string>> WritePlots(const std::string& directory, const PlotFiles& files,
                                              const std::string& format);

// `calibrate`: nothing without --plots_dir; otherwise draws, writes, lists the files in the JSON
// ("plots") and adds a "plot:" line per file to the summary.
Status AddCalibrationPlots(const CalibrateOptions& flags, const std::function<PlotFiles()>& draw,
                           nlohmann::ordered_json* json, std::string* summary);

}  // namespace calib::cli

#endif  // CALIB_TOOLS_COMMANDS_PLOT_OUTPUT_H_
