#include <calib/core/text_format.h>
#include <calib/tools/report/json_output.h>
#include <calib/tools/report/svg_plot.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

namespace calib {
namespace {

namespace fs = std::filesystem;

// --- Log-log panels ----------------------------------------------------------------------------

constexpr double kPanelWidth = 480, kPanelHeight = 380;
constexpr double kLeft = 70, kRight = 20, kTop = 40, kBottom = 50;  // Plot-area margins.

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!(v > 0) || !std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  // Widened by a margin in log space so that points do not sit on the frame.
  void Pad() {
    const double margin = std::max(0.05 * std::log10(hi / lo), 0.05);
    lo /= std::pow(10.0, margin);
    hi *= std::pow(10.0, margin);
  }
  double Fraction(double v) const { return std::log10(v / lo) / std::log10(hi / lo); }
};

// Ticks at "nice" mantissas inside the range, denser when the range is narrow.
std::vector<double> LogTicks(const Range& r) {
  const double decades = std::log10(r.hi / r.lo);
  const std::vector<double> mantissas = decades > 2.5   ? std::vector<double>{1}
                                        : decades > 1.2 ? std::vector<double>{1, 2, 5}
                                                        : std::vector<double>{1, 1.5, 2, 3, 5, 7};
  std::vector<double> ticks;
  for (int e = static_cast<int>(std::floor(std::log10(r.lo))); e <= std::ceil(std::log10(r.hi));
       ++e) {
    for (double m : mantissas) {
      const double v = m * std::pow(10.0, e);
      if (v >= r.lo && v <= r.hi) ticks.push_back(v);
    }
  }
  return ticks;
}

// The distinct x values of the data when there are at most 8, else nice ticks.
std::vector<double> XTicks(const PlotPanel& panel, const Range& r) {
  std::vector<double> xs;
  for (const PlotSeries& s : panel.series) {
    for (double x : s.x) {
      if (x > 0 && std::find(xs.begin(), xs.end(), x) == xs.end()) xs.push_back(x);
    }
  }
  if (xs.size() > 8) return LogTicks(r);
  std::sort(xs.begin(), xs.end());
  return xs;
}

std::string Marker(const PlotSeries& s, double x, double y) {
  if (s.marker == "ring") {
    return Format(
        "<circle cx='%.1f' cy='%.1f' r='5.5' fill='none' stroke='%s' stroke-width='1.5'/>\n", x, y,
        s.color.c_str());
  }
  if (s.marker == "square") {
    return Format("<rect x='%.1f' y='%.1f' width='7' height='7' fill='%s'/>\n", x - 3.5, y - 3.5,
                  s.color.c_str());
  }
  return Format("<circle cx='%.1f' cy='%.1f' r='3' fill='%s'/>\n", x, y, s.color.c_str());
}

// A panel's plot area and axes.
struct LogAxes {
  Range rx, ry;
  double left, right, top, bottom;
  double X(double x) const { return left + rx.Fraction(x) * (right - left); }
  double Y(double y) const { return bottom - ry.Fraction(y) * (bottom - top); }
};

void DrawLogAxes(const PlotPanel& panel, const LogAxes& a, double x0, std::ostringstream& svg) {
  svg << Format("<rect x='%.1f' y='%.1f' width='%.1f' height='%.1f' fill='none' stroke='#444'/>\n",
                a.left, a.top, a.right - a.left, a.bottom - a.top);
  svg << Format("<text x='%.1f' y='%.1f' text-anchor='middle' font-size='14'>%s</text>\n",
                (a.left + a.right) / 2, a.top - 10, SvgEscape(panel.title).c_str());
  for (double t : XTicks(panel, a.rx)) {
    svg << Format("<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='#ddd'/>\n", a.X(t), a.top,
                  a.X(t), a.bottom);
    svg << Format("<text x='%.1f' y='%.1f' text-anchor='middle' font-size='11'>%g</text>\n", a.X(t),
                  a.bottom + 15, t);
  }
  for (double t : LogTicks(a.ry)) {
    svg << Format("<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='#ddd'/>\n", a.left, a.Y(t),
                  a.right, a.Y(t));
    svg << Format("<text x='%.1f' y='%.1f' text-anchor='end' font-size='11'>%g</text>\n",
                  a.left - 4, a.Y(t) + 4, t);
  }
  svg << Format("<text x='%.1f' y='%.1f' text-anchor='middle' font-size='12'>%s</text>\n",
                (a.left + a.right) / 2, a.bottom + 35, SvgEscape(panel.x_label).c_str());
  svg << Format(
      "<text transform='translate(%.1f,%.1f) rotate(-90)' text-anchor='middle' "
      "font-size='12'>%s</text>\n",
      x0 + 18, (a.top + a.bottom) / 2, SvgEscape(panel.y_label).c_str());
}

void DrawLogPanel(const PlotPanel& panel, double x0, std::ostringstream& svg) {
  LogAxes a;
  for (const PlotSeries& s : panel.series) {
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (s.x[i] > 0 && s.y[i] > 0) {
        a.rx.Add(s.x[i]);
        a.ry.Add(s.y[i]);
      }
    }
  }
  if (!(a.rx.lo < a.rx.hi) || !(a.ry.lo < a.ry.hi)) return;
  a.rx.Pad();
  a.ry.Pad();
  a.left = x0 + kLeft;
  a.right = x0 + kPanelWidth - kRight;
  a.top = kTop + 30;
  a.bottom = kTop + 30 + kPanelHeight - kTop - kBottom;
  DrawLogAxes(panel, a, x0, svg);
  for (size_t k = 0; k < panel.series.size(); ++k) {
    const PlotSeries& s = panel.series[k];
    std::string points;
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!(s.x[i] > 0 && s.y[i] > 0)) continue;
      points += Format("%.1f,%.1f ", a.X(s.x[i]), a.Y(s.y[i]));
      if (!s.dashed) svg << Marker(s, a.X(s.x[i]), a.Y(s.y[i]));
    }
    svg << Format("<polyline points='%s' fill='none' stroke='%s' stroke-width='1.5'%s/>\n",
                  points.c_str(), s.color.c_str(), s.dashed ? " stroke-dasharray='6,4'" : "");
    // Legend in the upper right corner.
    const double ly = a.top + 14 + 16 * k;
    svg << Format(
        "<line x1='%.1f' y1='%.1f' x2='%.1f' y2='%.1f' stroke='%s' stroke-width='2'%s/>\n",
        a.right - 170, ly - 4, a.right - 150, ly - 4, s.color.c_str(),
        s.dashed ? " stroke-dasharray='6,4'" : "");
    if (!s.dashed) svg << Marker(s, a.right - 160, ly - 4);
    svg << Format("<text x='%.1f' y='%.1f' font-size='11'>%s</text>\n", a.right - 145, ly,
                  SvgEscape(s.label).c_str());
  }
}

}  // namespace

std::string SvgEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (c == '&') {
      out += "&amp;";
    } else {
      out += c;
    }
  }
  return out;
}

std::string LogLogSvg(const std::string& title, const std::vector<PlotPanel>& panels) {
  const double width = kPanelWidth * std::max<size_t>(panels.size(), 1);
  const double height = kPanelHeight + 30;
  std::ostringstream svg;
  svg << Format(
      "<svg xmlns='http://www.w3.org/2000/svg' width='%.0f' height='%.0f' "
      "font-family='sans-serif'>\n",
      width, height);
  svg << Format("<rect width='100%%' height='100%%' fill='white'/>\n");
  svg << Format("<text x='%.1f' y='22' text-anchor='middle' font-size='15'>%s</text>\n", width / 2,
                SvgEscape(title).c_str());
  for (size_t i = 0; i < panels.size(); ++i) DrawLogPanel(panels[i], kPanelWidth * i, svg);
  svg << "</svg>\n";
  return svg.str();
}

Status WriteLogLogSvg(const std::string& path, const std::string& title,
                      const std::vector<PlotPanel>& panels) {
  return WriteTextFile(path, LogLogSvg(title, panels));
}

StatusOr<std::vector<std::string>> WritePlotFiles(const std::string& directory,
                                                  const PlotFiles& files) {
  std::error_code error;
  fs::create_directories(directory, error);
  if (error) {
    return Status::Io("cannot create the plot folder " + directory + ": " + error.message());
  }
  std::vector<std::string> written;
  for (const auto& [name, svg] : files) {
    const std::string path = (fs::path(directory) / name).string();
    CALIB_RETURN_IF_ERROR(WriteTextFile(path, svg));
    written.push_back(path);
  }
  return written;
}

}  // namespace calib
