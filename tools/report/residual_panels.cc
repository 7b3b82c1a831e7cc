#include <calib/core/text_format.h>
#include <calib/tools/report/residual_panels.h>

#include <algorithm>
#include <cmath>

namespace calib {

ChartPanel ResidualHistogramPanel(const std::string& title, const std::string& x_label,
                                  const std::vector<double>& values, const std::vector<bool>& used,
                                  double sigma, const std::string& sigma_text,
                                  const std::string& count_unit) {
  double reach = 4.0 * sigma;
  int used_count = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    if (!used[i] || !std::isfinite(values[i])) continue;
    reach = std::max(reach, std::abs(values[i]));
    ++used_count;
  }
  if (!(reach > 0.0)) reach = 1.0;
  reach *= 1.02;
  const int bins = std::clamp(static_cast<int>(2.0 * std::sqrt(used_count)) | 1, 11, 51);
  const double width = 2.0 * reach / bins;
  std::vector<double> centre(bins), used_bars(bins, 0.0), all_bars(bins, 0.0);
  for (int b = 0; b < bins; ++b) centre[b] = -reach + (b + 0.5) * width;
  int beyond = 0, rejected = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    rejected += used[i] ? 0 : 1;
    const int b = static_cast<int>(std::floor((values[i] + reach) / width));
    if (!std::isfinite(values[i]) || b < 0 || b >= bins) {
      ++beyond;
      continue;
    }
    all_bars[b] += 1.0;
    if (used[i]) used_bars[b] += 1.0;
  }
  ChartPanel panel;
  panel.title = title;
  panel.x_label = x_label;
  panel.y_label = count_unit + " per bin";
  ChartSeries all{"rejected (outliers)", centre, all_bars};
  all.style = ChartStyle::kBars;
  all.bar_width = width;
  all.color = "#f4a582";  // Light red and blue: bars under a dark dashed curve.
  ChartSeries inliers{"used", centre, used_bars};
  inliers.style = ChartStyle::kBars;
  inliers.bar_width = width;
  inliers.color = "#92c5de";
  ChartSeries density{"normal, " + sigma_text, {}, {}};
  density.style = ChartStyle::kDashedLine;
  density.color = kReferenceColor;
  for (int k = 0; k <= 200; ++k) {
    const double x = -reach + k * reach / 100.0, z = x / sigma;
    density.x.push_back(x);
    density.y.push_back(used_count * width * std::exp(-0.5 * z * z) /
                        (sigma * std::sqrt(2 * M_PI)));
  }
  if (rejected > 0) panel.series.push_back(all);
  panel.series.push_back(inliers);
  if (sigma > 0.0) panel.series.push_back(density);
  panel.note = Format("%d used, %d rejected", used_count, rejected) +
               (beyond > 0 ? Format(" (%d beyond the axis)", beyond) : std::string());
  return panel;
}

ChartPanel UsedRejectedScatter(const std::string& title, const std::string& x_label,
                               const std::string& y_label, const std::vector<double>& x,
                               const std::vector<double>& y, const std::vector<bool>& used,
                               const std::string& unit_of_count) {
  ChartSeries in{"used", {}, {}}, out{"rejected (outliers)", {}, {}};
  in.style = ChartStyle::kDots;
  in.color = kUsedColor;
  out.style = ChartStyle::kCrosses;
  out.color = kRejectedColor;
  for (size_t i = 0; i < x.size() && i < y.size() && i < used.size(); ++i) {
    ChartSeries& s = used[i] ? in : out;
    s.x.push_back(x[i]);
    s.y.push_back(y[i]);
  }
  ChartPanel panel;
  panel.title = title;
  panel.x_label = x_label;
  panel.y_label = y_label;
  panel.zero_line = true;
  panel.series = {in, out};
  panel.note = Format("%zu %s: %zu used, %zu rejected", in.x.size() + out.x.size(),
                      unit_of_count.c_str(), in.x.size(), out.x.size());
  return panel;
}

}  // namespace calib
