#include <calib/core/text_format.h>
#include <calib/tools/report/svg_chart.h>
#include <calib/tools/report/svg_plot.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace calib {
namespace {

constexpr double kMargin = 20;       // Around the figure.
constexpr double kAxisLeft = 78;     // Tick labels and the y label, left of a plot area.
constexpr double kCellRight = 36;    // Between panels.
constexpr double kPanelTitle = 30;   // Above a plot area.
constexpr double kBelowAxis = 48;    // Tick labels and the x label under a plot area.
constexpr double kLegendRow = 17;    // One row of the legend (and the note).
constexpr double kCharWidth = 6.4;   // Of a 12 px sans-serif character, roughly.
constexpr double kCaptionLine = 17;  // Caption line height.

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  double Span() const { return hi - lo; }
  // A 5 % margin; a single value becomes a unit-wide range about it.
  void Pad() {
    if (!(lo <= hi)) lo = 0.0, hi = 1.0;
    if (!(hi > lo)) {
      const double half = lo == 0.0 ? 1.0 : 0.5 * std::abs(lo);
      lo -= half;
      hi += half;
    }
    const double pad = 0.05 * Span();
    lo -= pad;
    hi += pad;
  }
  void Widen(double span) {
    const double centre = 0.5 * (lo + hi);
    lo = centre - 0.5 * span;
    hi = centre + 0.5 * span;
  }
};

// Round tick positions covering [lo, hi], and the step between them.
std::vector<double> Ticks(const Range& r, double* step_out) {
  const double raw = r.Span() / 5.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * magnitude;
    if (step >= raw) break;
  }
  std::vector<double> ticks;
  for (double t = std::ceil(r.lo / step) * step; t <= r.hi + 1e-9 * step; t += step) {
    ticks.push_back(std::abs(t) < 1e-9 * step ? 0.0 : t);
  }
  *step_out = step;
  return ticks;
}

// As many decimals as the step needs, so that no two ticks read the same.
std::string TickText(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  return Format("%.*f", decimals, value);
}

std::vector<std::string> Wrap(const std::string& text, double width_px) {
  const size_t columns = static_cast<size_t>(std::max(20.0, width_px / kCharWidth));
  std::vector<std::string> lines;
  std::istringstream words(text);
  std::string word, line;
  while (words >> word) {
    if (!line.empty() && line.size() + 1 + word.size() > columns) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

// Legend entries laid out in rows under the plot area: (row, x offset) per listed series.
struct LegendSlot {
  size_t series;
  int row;
  double x;
};
std::vector<LegendSlot> LegendLayout(const ChartPanel& panel, double width) {
  std::vector<LegendSlot> slots;
  int row = 0;
  double x = 0;
  for (size_t k = 0; k < panel.series.size(); ++k) {
    const std::string& label = panel.series[k].label;
    if (label.empty()) continue;
    const double w = 34 + kCharWidth * label.size();
    if (x > 0 && x + w > width) ++row, x = 0;
    slots.push_back({k, row, x});
    x += w + 14;
  }
  return slots;
}
int LegendRows(const ChartPanel& panel, double width) {
  const std::vector<LegendSlot> slots = LegendLayout(panel, width);
  return (slots.empty() ? 0 : slots.back().row + 1) +
         static_cast<int>(Wrap(panel.note, width).size());
}

class PanelDrawer {
 public:
  PanelDrawer(const ChartPanel& panel, double left, double top, double width, double height)
      : p_(panel), left_(left), top_(top), w_(width), h_(height) {
    for (const ChartSeries& s : panel.series) {
      for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
        const double half = s.style == ChartStyle::kBars ? 0.5 * s.bar_width : 0.0;
        const bool bars = s.style == ChartStyle::kErrorBars || s.style == ChartStyle::kErrorDots;
        const double e = bars && i < s.error.size() ? s.error[i] : 0.0;
        rx_.Add(s.x[i] - half);
        rx_.Add(s.x[i] + half);
        ry_.Add(s.y[i] - e);
        ry_.Add(s.y[i] + e);
        if (s.style == ChartStyle::kBars) ry_.Add(0.0);
      }
    }
    rx_.Pad();
    ry_.Pad();
    if (p_.equal_aspect) {
      const double scale = std::max(rx_.Span() / w_, ry_.Span() / h_);
      rx_.Widen(scale * w_);
      ry_.Widen(scale * h_);
    }
  }

  void Draw(std::ostringstream& svg) const {
    svg << Format("<text x='%.1f' y='%.1f' text-anchor='middle' font-size='14'>%s</text>\n",
                  left_ + w_ / 2, top_ - 10, SvgEscape(p_.title).c_str());
    Axes(svg);
    svg << Format(
        "<clipPath id='clip%.0f_%.0f'><rect x='%.1f' y='%.1f' width='%.1f' "
        "height='%.1f'/></clipPath><g clip-path='url(#clip%.0f_%.0f)'>\n",
        left_, top_, left_, top_, w_, h_, left_, top_);
    for (const ChartSeries& s : p_.series) Series(s, svg);
    svg << "</g>\n";
    Legend(svg);
  }

 private:
  double X(double x) const { return left_ + (x - rx_.lo) / rx_.Span() * w_; }
  double Y(double y) const { return top_ + h_ - (y - ry_.lo) / ry_.Span() * h_; }

  void Axes(std::ostringstream& svg) const {
    const double bottom = top_ + h_;
    double step = 1.0;
    std::vector<double> x_ticks = Ticks(rx_, &step);
    if (p_.integer_x && rx_.Span() <= 30.0) {
      x_ticks.clear();
      for (double t = std::ceil(rx_.lo); t <= rx_.hi; t += 1.0) x_ticks.push_back(t);
      step = 1.0;
    }
    for (double t : x_ticks) {
      svg << Format("<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='#e4e4e4'/>", X(t), top_,
                    X(t), bottom);
      svg << Format("<text x='%.1f' y='%.1f' text-anchor='middle' font-size='11'>%s</text>\n", X(t),
                    bottom + 15, TickText(t, step).c_str());
    }
    for (double t : Ticks(ry_, &step)) {
      const bool zero = p_.zero_line && t == 0.0;
      svg << Format("<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='%s'/>", left_, Y(t),
                    left_ + w_, Y(t), zero ? "#555" : "#e4e4e4");
      svg << Format("<text x='%.1f' y='%.1f' text-anchor='end' font-size='11'>%s</text>\n",
                    left_ - 5, Y(t) + 4, TickText(t, step).c_str());
    }
    svg << Format(
        "<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='none' "
        "stroke='#444'/>\n",
        left_, top_, w_, h_);
    svg << Format("<text x='%.1f' y='%.1f' text-anchor='middle' font-size='12'>%s</text>\n",
                  left_ + w_ / 2, bottom + 34, SvgEscape(p_.x_label).c_str());
    svg << Format(
        "<text transform='translate(%.1f,%.1f) rotate(-90)' text-anchor='middle' "
        "font-size='12'>%s</text>\n",
        left_ - kAxisLeft + 16, top_ + h_ / 2, SvgEscape(p_.y_label).c_str());
  }

  // One mark of a series at pixel (x, y).
  static std::string Mark(const ChartSeries& s, double x, double y) {
    const char* c = s.color.c_str();
    switch (s.style) {
      case ChartStyle::kCrosses:
        return Format(
            "<path d='M%.1f %.1fl6 6m0 -6l-6 6' stroke='%s' stroke-width='1.4' fill='none'/>",
            x - 3, y - 3, c);
      case ChartStyle::kErrorBars:
        return Format("<rect x='%.1f' y='%.1f' width='7' height='7' fill='%s'/>", x - 3.5, y - 3.5,
                      c);
      case ChartStyle::kErrorDots:
        return Format("<circle cx='%.1f' cy='%.1f' r='4' fill='%s'/>", x, y, c);
      case ChartStyle::kStar:
        return Format("<circle cx='%.1f' cy='%.1f' r='7' fill='%s' stroke='#000'/>", x, y, c);
      default:
        return Format("<circle cx='%.1f' cy='%.1f' r='2.6' fill='%s' fill-opacity='0.75'/>", x, y,
                      c);
    }
  }

  // Each series in a group that names it and counts its points (for tests and scripts).
  void Series(const ChartSeries& s, std::ostringstream& svg) const {
    const size_t n = std::min(s.x.size(), s.y.size());
    std::string name;
    for (char c : SvgEscape(s.label)) name += c == '\'' ? std::string("&apos;") : std::string(1, c);
    svg << Format("<g data-series='%s' data-points='%zu'>", name.c_str(), n);
    SeriesMarks(s, n, svg);
    svg << "</g>\n";
  }

  void SeriesMarks(const ChartSeries& s, size_t n, std::ostringstream& svg) const {
    if (s.style == ChartStyle::kLine || s.style == ChartStyle::kDashedLine) {
      svg << "<polyline fill='none' stroke='" << s.color << "' stroke-width='1.8'"
          << (s.style == ChartStyle::kDashedLine ? " stroke-dasharray='7,4'" : "") << " points='";
      for (size_t i = 0; i < n; ++i) svg << Format("%.1f,%.1f ", X(s.x[i]), Y(s.y[i]));
      svg << "'/>";
      return;
    }
    for (size_t i = 0; i < n; ++i) {
      const double x = X(s.x[i]) + s.offset_px, y = Y(s.y[i]);
      if (s.style == ChartStyle::kBars) {
        const double x0 = X(s.x[i] - 0.5 * s.bar_width), x1 = X(s.x[i] + 0.5 * s.bar_width);
        const double y0 = Y(0.0);
        svg << Format(
            "<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='%s' stroke='#ffffff' "
            "stroke-width='0.5'/>",
            x0, std::min(y, y0), std::max(x1 - x0, 0.5), std::abs(y0 - y), s.color.c_str());
        continue;
      }
      const bool bars = s.style == ChartStyle::kErrorBars || s.style == ChartStyle::kErrorDots;
      if (bars && i < s.error.size()) {
        svg << Format(
            "<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='%s' "
            "stroke-width='1.5'/>",
            x, Y(s.y[i] - s.error[i]), x, Y(s.y[i] + s.error[i]), s.color.c_str());
      }
      svg << Mark(s, x, y);
    }
  }

  void Legend(std::ostringstream& svg) const {
    const double y0 = top_ + h_ + kBelowAxis + 4;
    int rows = 0;
    for (const LegendSlot& slot : LegendLayout(p_, w_)) {
      const ChartSeries& s = p_.series[slot.series];
      const double x = left_ + slot.x, y = y0 + kLegendRow * slot.row;
      rows = slot.row + 1;
      if (s.style == ChartStyle::kLine || s.style == ChartStyle::kDashedLine) {
        svg << Format(
            "<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='%s' "
            "stroke-width='2.2'%s/>",
            x, y - 4, x + 26, y - 4, s.color.c_str(),
            s.style == ChartStyle::kDashedLine ? " stroke-dasharray='7,4'" : "");
      } else if (s.style == ChartStyle::kBars) {
        svg << Format("<rect x='%.1f' y='%.1f' width='22' height='10' fill='%s'/>", x + 2, y - 9,
                      s.color.c_str());
      } else {
        svg << Mark(s, x + 13, y - 4);
      }
      svg << Format("<text x='%.1f' y='%.1f' font-size='12'>%s</text>\n", x + 32, y,
                    SvgEscape(s.label).c_str());
    }
    for (const std::string& line : Wrap(p_.note, w_)) {
      svg << Format("<text x='%.1f' y='%.1f' font-size='12' fill='#444'>%s</text>\n", left_,
                    y0 + kLegendRow * rows++, SvgEscape(line).c_str());
    }
  }

  const ChartPanel& p_;
  double left_, top_, w_, h_;
  Range rx_, ry_;
};

}  // namespace

std::string ChartSvg(const ChartFigure& figure) {
  const int columns = std::max(1, std::min<int>(figure.columns, figure.panels.size()));
  const int rows = (static_cast<int>(figure.panels.size()) + columns - 1) / columns;
  const double cell_width = kAxisLeft + figure.panel_width + kCellRight;
  const double width = 2 * kMargin + columns * cell_width;
  std::vector<std::string> caption;
  for (const std::string& paragraph : figure.caption) {
    for (std::string& line : Wrap(paragraph, width - 2 * kMargin)) caption.push_back(line);
  }
  // Each row as tall as its panel with the most legend rows.
  std::vector<double> row_height(rows, 0.0);
  for (size_t i = 0; i < figure.panels.size(); ++i) {
    const double h = kPanelTitle + figure.panel_height + kBelowAxis +
                     kLegendRow * LegendRows(figure.panels[i], figure.panel_width) + 16;
    row_height[i / columns] = std::max(row_height[i / columns], h);
  }
  const double header = 40 + kCaptionLine * caption.size() + 10;
  double height = header + kMargin;
  for (double h : row_height) height += h;

  std::ostringstream svg;
  svg << Format(
      "<svg xmlns='http://www.w3.org/2000/svg' width='%.0f' height='%.0f' "
      "font-family='DejaVu Sans, Arial, sans-serif'>\n",
      width, height);
  svg << "<rect width='100%' height='100%' fill='white'/>\n";
  svg << Format("<text x='%.1f' y='30' font-size='18' font-weight='bold'>%s</text>\n", kMargin,
                SvgEscape(figure.title).c_str());
  for (size_t i = 0; i < caption.size(); ++i) {
    svg << Format("<text x='%.1f' y='%.1f' font-size='12' fill='#333'>%s</text>\n", kMargin,
                  52 + kCaptionLine * i, SvgEscape(caption[i]).c_str());
  }
  double row_top = header;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const size_t i = static_cast<size_t>(r * columns + c);
      if (i >= figure.panels.size()) break;
      const double left = kMargin + c * cell_width + kAxisLeft;
      PanelDrawer(figure.panels[i], left, row_top + kPanelTitle, figure.panel_width,
                  figure.panel_height)
          .Draw(svg);
    }
    row_top += row_height[r];
  }
  svg << "</svg>\n";
  return svg.str();
}

ChartSeries PathSeries(const std::string& label, const std::vector<Pose2d>& path, const char* color,
                       ChartStyle style) {
  ChartSeries s{label, {}, {}};
  for (const Pose2d& p : path) {
    s.x.push_back(p(0));
    s.y.push_back(p(1));
  }
  s.color = color;
  s.style = style;
  return s;
}

}  // namespace calib
