#include <calib/tools/report/residual_panels.h>
#include <calib/tools/report/svg_chart.h>
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "tests/tools/svg_check.h"

namespace calib {
namespace {

using testing::HasText;
using testing::SvgSeriesPoints;
using testing::SvgStructureError;
using testing::SvgTexts;

ChartFigure OnePanel(const std::vector<double>& x, const std::vector<double>& y) {
  ChartPanel panel;
  panel.title = "A panel & its <title>";
  panel.x_label = "x [m]";
  panel.y_label = "y [m]";
  ChartSeries s("the data", x, y);
  s.style = ChartStyle::kDots;
  panel.series = {s};
  ChartFigure figure;
  figure.title = "A figure";
  figure.caption = {
      "What it shows, in words long enough to be wrapped over more than one line of "
      "the caption, so that the wrapping is exercised by the test as well."};
  figure.panels = {panel};
  return figure;
}

TEST(SvgChartTest, WellFormedWithEscapedTextAndCountedSeries) {
  const std::string svg = ChartSvg(OnePanel({0, 1, 2}, {0, 1, 4}));
  EXPECT_EQ(SvgStructureError(svg), "");
  EXPECT_TRUE(HasText(svg, "A panel &amp; its &lt;title&gt;"));
  EXPECT_TRUE(HasText(svg, "x [m]"));
  EXPECT_TRUE(HasText(svg, "the data"));
  EXPECT_EQ(SvgSeriesPoints(svg).at("the data"), 3);
}

TEST(SvgChartTest, TickLabelsNeverRepeatOnANarrowRange) {
  // Bin means like 0.00014, 0.00018, 0.00025 once read "0.00014, 0.00018, ..." with repeats at
  // two significant digits; the ticks take as many decimals as their step needs.
  const std::string svg = ChartSvg(OnePanel({0.000141, 0.000183, 0.000252}, {1.0, 1.001, 1.0021}));
  std::vector<std::string> ticks;
  for (const std::string& t : SvgTexts(svg)) {
    if (!t.empty() && (std::isdigit(static_cast<unsigned char>(t[0])) || t[0] == '-')) {
      ticks.push_back(t);
    }
  }
  ASSERT_GE(ticks.size(), 6u);
  EXPECT_EQ(std::set<std::string>(ticks.begin(), ticks.end()).size(), ticks.size());
}

TEST(SvgChartTest, HistogramCountsUsedAndRejected) {
  const std::vector<double> values = {-1.0, -0.2, 0.0, 0.1, 0.5, 9.0, -0.3};
  const std::vector<bool> used = {true, true, true, true, true, false, false};
  const ChartPanel panel =
      ResidualHistogramPanel("Residual", "error [mm]", values, used, 0.5, "σ = 0.5 mm", "samples");
  EXPECT_EQ(panel.note, "5 used, 2 rejected (1 beyond the axis)");
  EXPECT_EQ(panel.y_label, "samples per bin");
  double used_total = 0.0;
  for (const ChartSeries& s : panel.series) {
    if (s.label == "used") {
      for (double y : s.y) used_total += y;
    }
  }
  EXPECT_EQ(used_total, 5.0);
}

TEST(SvgChartTest, ScatterSplitsUsedFromRejected) {
  const ChartPanel panel = UsedRejectedScatter("Coverage", "v [m/s]", "ω [deg/s]", {1, 2, 3},
                                               {0, 0, 1}, {true, false, true}, "intervals");
  ChartFigure figure;
  figure.panels = {panel};
  const auto counts = SvgSeriesPoints(ChartSvg(figure));
  EXPECT_EQ(counts.at("used"), 2);
  EXPECT_EQ(counts.at("rejected (outliers)"), 1);
  EXPECT_EQ(panel.note, "3 intervals: 2 used, 1 rejected");
}

}  // namespace
}  // namespace calib
