#ifndef CALIB_TOOLS_REPORT_RESIDUAL_PANELS_H_
#define CALIB_TOOLS_REPORT_RESIDUAL_PANELS_H_

#include <calib/tools/report/svg_chart.h>

#include <string>
#include <vector>

// Panels shared by the calibration plots of both problems.
namespace calib {

// Colours of the calibration plots: the sensor's own path or the used samples, the rejected
// samples, the "before" parameters, the calibrated ones.
inline constexpr const char* kUsedColor = "#2166ac";
inline constexpr const char* kRejectedColor = "#d6604d";
inline constexpr const char* kBeforeColor = "#e08214";
inline constexpr const char* kCalibratedColor = "#1b7837";
inline constexpr const char* kReferenceColor = "#222222";

// A histogram of residuals in display units: the used samples' bars stacked on the rejected ones
// (in a colour of their own), and the normal density of the fitted σ scaled to the used count.
// The axis spans the used residuals (at least ±4σ); rejected ones beyond it are counted in the
// note.
ChartPanel ResidualHistogramPanel(const std::string& title, const std::string& x_label,
                                  const std::vector<double>& values, const std::vector<bool>& used,
                                  double sigma, const std::string& sigma_text,
                                  const std::string& count_unit);

// A scatter of used samples (dots) and rejected ones (crosses), with the counts in the note.
ChartPanel UsedRejectedScatter(const std::string& title, const std::string& x_label,
                               const std::string& y_label, const std::vector<double>& x,
                               const std::vector<double>& y, const std::vector<bool>& used,
                               const std::string& unit_of_count);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_RESIDUAL_PANELS_H_
