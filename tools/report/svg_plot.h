#ifndef CALIB_TOOLS_REPORT_SVG_PLOT_H_
#define CALIB_TOOLS_REPORT_SVG_PLOT_H_

#include <calib/core/status.h>
#include <calib/solvers/stats/change_point.h>

#include <string>
#include <utility>
#include <vector>

// The one SVG writer of calib and calib_bench (no plotting dependency for a few figures):
// binned residual profiles (`calib diagnose`) and log-log line plots (the benchmarks).
namespace calib {

// Text with <, > and & escaped for SVG.
std::string SvgEscape(const std::string& text);

// Binned means ± 2 standard errors of a covariate profile, before (base model) and after (with
// the adopted effects), one panel per channel, two panels a row (covariate_profile_plot.cc): at
// the bins' true positions when they are spread evenly enough, else as numbered bins with their
// means listed; the "along the effect" panel explained in the caption.
std::string CovariateProfileSvg(const CovariateProfile& profile, const std::string& title);

// Words for the titles: "lateral_slip" → "Lateral slip", "v_times_omega" → "v·ω (centripetal
// acceleration)"; unknown names with their underscores as spaces.
std::string EffectInWords(const std::string& name);
std::string CovariateInWords(const std::string& name);

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  std::string color = "#000000";
  bool dashed = false;  // Dashed line without markers (a reference such as a bound).
  // "circle", "ring" (open, larger: stays visible over a series it coincides with), "square".
  std::string marker = "circle";
};

struct PlotPanel {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
};

// Log-log panels side by side under a common title; non-positive points are skipped. The x
// ticks are the data's x values when there are few of them.
std::string LogLogSvg(const std::string& title, const std::vector<PlotPanel>& panels);
Status WriteLogLogSvg(const std::string& path, const std::string& title,
                      const std::vector<PlotPanel>& panels);

// Files to write, (file name, content), and the writer (creates the folder; returns the paths
// written, or an error naming the file that failed).
using PlotFiles = std::vector<std::pair<std::string, std::string>>;
StatusOr<std::vector<std::string>> WritePlotFiles(const std::string& directory,
                                                  const PlotFiles& files);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_SVG_PLOT_H_
