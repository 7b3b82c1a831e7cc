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

// --- Covariate profiles (linear axes) --------------------------------------------------------

constexpr double kProfileWidth = 430, kProfileHeight = 250, kProfileLeft = 70, kProfileTop = 84;
constexpr double kProfileGapX = 40, kProfileGapY = 84;

// Round tick positions covering [lo, hi].
std::vector<double> LinearTicks(double lo, double hi) {
  const double range = hi - lo;
  if (!(range > 0.0)) return {lo};
  const double raw = range / 5.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * magnitude;
    if (step >= raw) break;
  }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) {
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  }
  return ticks;
}

std::string TickLabel(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}

// One channel's panel at (ox, oy): frame, ticks, bin labels, then both fits' means ± 2 SE.
class ProfilePanel {
 public:
  ProfilePanel(const CovariateProfile& profile, int channel, double scale, double ox, double oy)
      : profile_(profile), c_(channel), scale_(scale), ox_(ox), oy_(oy) {
    bins_ = profile.center.size();
    for (size_t b = 0; b < bins_; ++b) {
      Extend(profile.before_mean, profile.before_stderr, b);
      Extend(profile.after_mean, profile.after_stderr, b);
    }
    if (!(y_hi_ > y_lo_)) y_hi_ = y_lo_ + 1.0;
    const double pad = 0.05 * (y_hi_ - y_lo_);
    y_lo_ -= pad;
    y_hi_ += pad;
  }

  void Draw(const std::string& label, std::ostringstream& svg) const {
    svg << "<rect x=\"" << ox_ << "\" y=\"" << oy_ << "\" width=\"" << kProfileWidth
        << "\" height=\"" << kProfileHeight << "\" fill=\"none\" stroke=\"#888\"/>\n";
    for (double t : LinearTicks(y_lo_, y_hi_)) {
      svg << "<line x1=\"" << ox_ << "\" x2=\"" << ox_ + kProfileWidth << "\" y1=\"" << Y(t)
          << "\" y2=\"" << Y(t) << "\" stroke=\"" << (t == 0.0 ? "#444" : "#eee") << "\"/>";
      svg << "<text x=\"" << ox_ - 6 << "\" y=\"" << Y(t) + 4 << "\" text-anchor=\"end\">"
          << TickLabel(t) << "</text>\n";
    }
    const double bottom = oy_ + kProfileHeight;
    for (size_t b = 0; b < bins_; ++b) {
      char text[32];
      std::snprintf(text, sizeof(text), "%.2g", profile_.center[b]);
      svg << "<line x1=\"" << X(b) << "\" x2=\"" << X(b) << "\" y1=\"" << bottom << "\" y2=\""
          << bottom + 4 << "\" stroke=\"#888\"/>";
      svg << "<text font-size=\"10\" text-anchor=\"end\" transform=\"translate(" << X(b) + 3 << ","
          << bottom + 12 << ") rotate(-35)\">" << text << "</text>\n";
    }
    svg << "<text x=\"" << ox_ + kProfileWidth / 2 << "\" y=\"" << oy_ - 8
        << "\" text-anchor=\"middle\">" << label << "</text>\n";
    svg << "<text x=\"" << ox_ + kProfileWidth / 2 << "\" y=\"" << bottom + 48
        << "\" text-anchor=\"middle\" fill=\"#555\">" << SvgEscape(profile_.name) << " ["
        << SvgEscape(profile_.unit) << "], bins of equal count</text>\n";
    Series(profile_.before_mean, profile_.before_stderr, "#d95f02", false, -2.0, svg);
    Series(profile_.after_mean, profile_.after_stderr, "#1b7837", true, 2.0, svg);
  }

 private:
  void Extend(const std::vector<Eigen::VectorXd>& means,
              const std::vector<Eigen::VectorXd>& stderrs, size_t b) {
    if (b >= means.size()) return;
    const double m = means[b](c_) * scale_, e = 2.0 * stderrs[b](c_) * scale_;
    y_lo_ = std::min(y_lo_, m - e);
    y_hi_ = std::max(y_hi_, m + e);
  }
  // Bins hold equal counts, so they are drawn at equal spacing (the covariate's quantiles) and
  // labelled with their mean covariate.
  double X(double b) const { return ox_ + (b + 0.5) / bins_ * kProfileWidth; }
  double Y(double y) const {
    return oy_ + kProfileHeight - (y - y_lo_) / (y_hi_ - y_lo_) * kProfileHeight;
  }
  void Series(const std::vector<Eigen::VectorXd>& means,
              const std::vector<Eigen::VectorXd>& stderrs, const char* colour, bool square,
              double shift, std::ostringstream& svg) const {
    std::ostringstream line;
    for (size_t b = 0; b < means.size() && b < bins_; ++b) {
      const double x = X(b) + shift;
      const double m = means[b](c_) * scale_, e = 2.0 * stderrs[b](c_) * scale_;
      line << (b ? " " : "") << x << "," << Y(m);
      svg << "<line x1=\"" << x << "\" x2=\"" << x << "\" y1=\"" << Y(m - e) << "\" y2=\""
          << Y(m + e) << "\" stroke=\"" << colour << "\"/>";
      if (square) {
        svg << "<rect x=\"" << x - 3.5 << "\" y=\"" << Y(m) - 3.5
            << "\" width=\"7\" height=\"7\" fill=\"" << colour << "\"/>";
      } else {
        svg << "<circle cx=\"" << x << "\" cy=\"" << Y(m) << "\" r=\"4\" fill=\"" << colour
            << "\"/>";
      }
    }
    svg << "\n<polyline points=\"" << line.str() << "\" fill=\"none\" stroke=\"" << colour
        << "\" stroke-width=\"1.2\"/>\n";
  }

  const CovariateProfile& profile_;
  int c_;
  double scale_, ox_, oy_;
  size_t bins_ = 0;
  double y_lo_ = 0.0, y_hi_ = 0.0;
};

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

std::string CovariateProfileSvg(const CovariateProfile& profile, const std::string& title) {
  const int channels =
      profile.before_mean.empty() ? 0 : static_cast<int>(profile.before_mean[0].size());
  std::vector<std::string> labels = {"x error [mm]", "y error [mm]", "θ error [mrad]",
                                     "along the effect [σ]"};
  std::vector<double> scales = {1e3, 1e3, 1e3, 1.0};
  if (!profile.channel_labels.empty()) {
    labels = profile.channel_labels;
    scales = profile.channel_scales;
  }
  const int columns = 2, rows = (channels + 1) / 2;
  const double left = kProfileLeft;
  const double width = left + columns * (kProfileWidth + kProfileGapX),
               height = kProfileTop + rows * (kProfileHeight + kProfileGapY) + 20;
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  svg << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg << "<text x=\"" << left << "\" y=\"24\" font-size=\"16\">" << SvgEscape(title) << "</text>\n";
  svg << "<text x=\"" << left << "\" y=\"46\" fill=\"#d95f02\">● before (base model)</text>";
  svg << "<text x=\"" << left + 170
      << "\" y=\"46\" fill=\"#1b7837\">■ after (with the adopted effects)</text>";
  svg << "<text x=\"" << left + 460
      << "\" y=\"46\" fill=\"#555\">binned means ± 2 standard errors</text>\n";
  if (!profile.center.empty()) {
    for (int c = 0; c < channels; ++c) {
      const double ox = left + (c % columns) * (kProfileWidth + kProfileGapX);
      const double oy = kProfileTop + (c / columns) * (kProfileHeight + kProfileGapY);
      ProfilePanel(profile, c, scales[c], ox, oy).Draw(labels[c], svg);
    }
  }
  svg << "</svg>\n";
  return svg.str();
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
