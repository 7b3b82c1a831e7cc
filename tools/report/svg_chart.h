#ifndef CALIB_TOOLS_REPORT_SVG_CHART_H_
#define CALIB_TOOLS_REPORT_SVG_CHART_H_

#include <calib/core/se2.h>

#include <string>
#include <utility>
#include <vector>

// Figures of panels on linear axes (paths, histograms, scatter plots, binned means with error
// bars) for `calib calibrate` and `calib diagnose`: a title and a caption in words above, each
// panel with its title, axis labels with units and a legend below it, so that nothing is drawn
// over the data.
namespace calib {

enum class ChartStyle {
  kLine,        // Polyline.
  kDashedLine,  // Dashed polyline (a reference: a fitted density, a seed).
  kDots,        // Filled circles.
  kCrosses,     // × marks (rejected samples).
  kBars,        // Histogram bars centred on x, `bar_width` wide, from 0 to y.
  kErrorBars,   // Squares at (x, y) with vertical bars y ± error.
  kErrorDots,   // Circles at (x, y) with vertical bars y ± error.
  kStar,        // A large marker (a landmark, a start point).
};

struct ChartSeries {
  ChartSeries() = default;
  ChartSeries(std::string label_in, std::vector<double> x_in, std::vector<double> y_in)
      : label(std::move(label_in)), x(std::move(x_in)), y(std::move(y_in)) {}

  std::string label;  // In the legend; empty: not listed.
  std::vector<double> x, y;
  std::vector<double> error;  // kErrorBars: half-length of each bar.
  std::string color = "#000000";
  ChartStyle style = ChartStyle::kLine;
  double bar_width = 0.0;  // kBars.
  double offset_px = 0.0;  // Drawn shifted right by this (two error-bar series side by side).
};

// A path of poses as a series of their (x, y).
ChartSeries PathSeries(const std::string& label, const std::vector<Pose2d>& path, const char* color,
                       ChartStyle style);

struct ChartPanel {
  std::string title;             // In words.
  std::string x_label, y_label;  // With units, e.g. "x [m]".
  std::vector<ChartSeries> series;
  bool equal_aspect = false;  // One unit on x as long as one on y (paths).
  bool zero_line = false;     // A darker line at y = 0.
  bool integer_x = false;     // x ticks at every integer (numbered bins).
  std::string note;           // A line under the legend (counts, a fitted σ).
};

struct ChartFigure {
  std::string title;
  std::vector<std::string> caption;  // Paragraphs, wrapped to the figure's width.
  std::vector<ChartPanel> panels;
  int columns = 2;
  double panel_width = 440, panel_height = 300;  // Plot area of each panel (px).
};

std::string ChartSvg(const ChartFigure& figure);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_SVG_CHART_H_
