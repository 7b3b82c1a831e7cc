#ifndef CALIB_BENCHMARKS_BENCH_PLOT_H_
#define CALIB_BENCHMARKS_BENCH_PLOT_H_

#include <string>
#include <vector>

#include <calib/core/status.h>

// A minimal SVG writer for log-log line plots (no plotting dependency for one figure).
namespace calib::bench {

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

// Panels side by side under a common title; non-positive points are skipped. The x ticks are
// the data's x values when there are few of them.
Status WriteLogLogSvg(const std::string& path, const std::string& title,
                      const std::vector<PlotPanel>& panels);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_PLOT_H_
