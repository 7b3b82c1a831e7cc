#include <calib/tools/commands/plot_output.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace calib::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kRasterizer = "rsvg-convert";

bool OnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (!dir.empty() && ::access((fs::path(dir) / program).c_str(), X_OK) == 0) return true;
  }
  return false;
}

// 'text' for the shell.
std::string Quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

StatusOr<std::string> Rasterize(const std::string& svg) {
  const std::string png = fs::path(svg).replace_extension(".png").string();
  const std::string command =
      std::string(kRasterizer) + " -o " + Quoted(png) + " " + Quoted(svg) + " 2>/dev/null";
  const int status = std::system(command.c_str());
  if (status != 0 || !fs::exists(png)) {
    return Status::Io(std::string(kRasterizer) + " could not convert " + svg + " to " + png);
  }
  return png;
}

}  // namespace

Status CheckPlotFormat(const std::string& format) {
  if (format != "svg" && format != "png") {
    return Status::InvalidInput("unknown --plot_format '" + format + "' (svg or png)");
  }
  if (format == "png" && !OnPath(kRasterizer)) {
    return Status::InvalidInput(
        "--plot_format png needs the program rsvg-convert (Debian/Ubuntu package librsvg2-bin: "
        "apt-get install librsvg2-bin), which is not on the PATH; --plot_format svg needs "
        "nothing");
  }
  return Status::Ok();
}

Status AddRasterized(const std::string& format, std::vector<std::string>* written) {
  CALIB_RETURN_IF_ERROR(CheckPlotFormat(format));
  if (format != "png") return Status::Ok();
  const size_t svgs = written->size();
  for (size_t i = 0; i < svgs; ++i) {
    CALIB_ASSIGN_OR_RETURN(std::string png, Rasterize((*written)[i]));
    written->push_back(std::move(png));
  }
  return Status::Ok();
}

StatusOr<std::vector<std::string>> WritePlots(const std::string& directory, const PlotFiles& files,
                                              const std::string& format) {
  CALIB_RETURN_IF_ERROR(CheckPlotFormat(format));
  CALIB_ASSIGN_OR_RETURN(std::vector<std::string> written, WritePlotFiles(directory, files));
  CALIB_RETURN_IF_ERROR(AddRasterized(format, &written));
  return written;
}

Status AddCalibrationPlots(const CalibrateOptions& flags, const std::function<PlotFiles()>& draw,
                           nlohmann::ordered_json* json, std::string* summary) {
  if (flags.plots_dir.empty()) return Status::Ok();
  CALIB_ASSIGN_OR_RETURN(const std::vector<std::string> plots,
                         WritePlots(flags.plots_dir, draw(), flags.plot_format));
  (*json)["plots"] = plots;
  for (const std::string& plot : plots) *summary += "  plot: " + plot + "\n";
  return Status::Ok();
}

}  // namespace calib::cli
