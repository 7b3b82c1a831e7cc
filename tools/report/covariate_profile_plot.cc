// The diagnose figures: binned residual profiles against a covariate (svg_plot.h).
#include <calib/core/text_format.h>
#include <calib/tools/report/svg_chart.h>
#include <calib/tools/report/svg_plot.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

namespace calib {
namespace {

std::string Spaced(std::string name) {
  std::replace(name.begin(), name.end(), '_', ' ');
  return name;
}

// Bins drawn at their means unless the gaps between them differ by more than this factor (bins
// of equal count under a peaked covariate crowd into a few pixels; then they are numbered).
constexpr double kMaxGapRatio = 6.0;

bool EvenlySpread(const std::vector<double>& centre) {
  if (centre.size() < 2) return false;
  std::vector<double> gaps;
  for (size_t b = 1; b < centre.size(); ++b) gaps.push_back(centre[b] - centre[b - 1]);
  const auto [lo, hi] = std::minmax_element(gaps.begin(), gaps.end());
  return *lo > 0.0 && *hi <= kMaxGapRatio * *lo;
}

// Panel title and y label of a channel from its axis label "x error [mm]".
std::string ChannelTitle(const std::string& label) {
  static const std::map<std::string, std::string> titles = {
      {"x error [mm]", "Forward (x) residual"},
      {"y error [mm]", "Sideways (y) residual"},
      {"θ error [mrad]", "Heading (θ) residual"},
      {"bearing error [mrad]", "Bearing residual"},
      {"along the effect [σ]", "Residual along the effect"}};
  const auto it = titles.find(label);
  return it != titles.end() ? it->second : label;
}

// Two significant digits; 0 for a value that is zero on the scale of the largest.
std::string ShortNumber(double v, double largest) {
  return std::abs(v) < 1e-4 * largest ? "0" : Format("%.2g", v);
}

}  // namespace

std::string EffectInWords(const std::string& name) {
  static const std::map<std::string, std::string> words = {
      {"time_offset", "Time offset"},
      {"lateral_slip", "Lateral slip"},
      {"longitudinal_slip", "Longitudinal slip"},
      {"wheel_radius_change", "Wheel-radius change"},
      {"speed_dependent_radius", "Speed-dependent wheel radius"},
      {"icr_offset_x", "Turning centre ahead of the axle"},
      {"scan_scale", "Scan scale error"},
      {"stamp_jitter", "Stamp jitter"}};
  const auto it = words.find(name);
  if (it != words.end()) return it->second;
  std::string text = Spaced(name);
  if (!text.empty()) text[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(text[0])));
  return text;
}

std::string CovariateInWords(const std::string& name) {
  static const std::map<std::string, std::string> words = {
      {"speed", "forward speed"},
      {"angular_rate", "angular rate"},
      {"v_times_omega", "v·ω (centripetal acceleration)"},
      {"acceleration", "forward acceleration"},
      {"angular_acceleration", "angular acceleration"},
      {"bearing_rate", "bearing rate"}};
  const auto it = words.find(name);
  return it != words.end() ? it->second : Spaced(name);
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
  const std::string covariate = CovariateInWords(profile.name);
  const bool true_positions = EvenlySpread(profile.center);
  const size_t bins = profile.center.size();
  std::vector<double> x(bins);
  for (size_t b = 0; b < bins; ++b) x[b] = true_positions ? profile.center[b] : b + 1.0;

  ChartFigure figure;
  figure.title = title;
  figure.caption.push_back(
      "Each point is the weighted mean residual of one bin of samples, the bins holding equal "
      "counts in order of " +
      covariate +
      "; bars: ± 2 standard errors. Orange: the base model; green: with the "
      "adopted effects. Structure the model leaves out shows as means away from zero.");
  bool along = false;
  for (int c = 0; c < channels && c < static_cast<int>(labels.size()); ++c) {
    along = along || labels[c].rfind("along the effect", 0) == 0;
  }
  if (along) {
    figure.caption.push_back(
        "Residual along the effect: each sample's whitened residual projected on the change "
        "the effect would make to its prediction, in σ. Away from zero before (orange), the "
        "effect explains that structure; on zero after (green), the adopted model has taken "
        "it up.");
  }
  if (!true_positions && bins > 0) {
    std::string means = "Bins are numbered (their means crowd together); mean " + covariate + " [" +
                        profile.unit + "] of each bin:";
    double largest = 0.0;
    for (double c : profile.center) largest = std::max(largest, std::abs(c));
    for (size_t b = 0; b < bins; ++b) {
      means += Format(" %zu: ", b + 1) + ShortNumber(profile.center[b], largest) +
               (b + 1 < bins ? "," : ".");
    }
    figure.caption.push_back(means);
  }
  for (int c = 0; c < channels && c < static_cast<int>(labels.size()); ++c) {
    ChartPanel panel;
    panel.title = ChannelTitle(labels[c]);
    panel.y_label = "mean " + labels[c];
    panel.x_label = true_positions ? covariate + " [" + profile.unit + "] (bin means)"
                                   : "bin of equal count, by " + covariate + " (1: lowest)";
    panel.zero_line = true;
    panel.integer_x = !true_positions;
    ChartSeries before("before: base model", x, {});
    ChartSeries after("after: with the adopted effects", x, {});
    for (size_t b = 0; b < bins; ++b) {
      if (b < profile.before_mean.size()) {
        before.y.push_back(profile.before_mean[b](c) * scales[c]);
        before.error.push_back(2.0 * profile.before_stderr[b](c) * scales[c]);
      }
      if (b < profile.after_mean.size()) {
        after.y.push_back(profile.after_mean[b](c) * scales[c]);
        after.error.push_back(2.0 * profile.after_stderr[b](c) * scales[c]);
      }
    }
    before.style = ChartStyle::kErrorDots;
    before.color = "#d95f02";
    before.offset_px = -3;
    after.style = ChartStyle::kErrorBars;
    after.color = "#1b7837";
    after.offset_px = 3;
    panel.series = {before, after};
    figure.panels.push_back(panel);
  }
  figure.columns = 2;
  figure.panel_width = 420;
  figure.panel_height = 230;
  return ChartSvg(figure);
}

}  // namespace calib
