#ifndef CALIB_TOOLS_REPORT_BEARING_CALIBRATION_PLOTS_H_
#define CALIB_TOOLS_REPORT_BEARING_CALIBRATION_PLOTS_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/tools/report/svg_plot.h>

// The plots of `calib calibrate --plots_dir` for the bearing-only problem:
//   bearing_paths.svg      per run, the robot path the bundle adjustment fits (bearings and
//                          encoders) against dead reckoning from its start with the nominal and
//                          the calibrated wheels, the landmark at the origin;
//   bearing_residuals.svg  the histogram of the bearing residuals with the fitted σβ;
//   bearing_coverage.svg   the (v, ω) between bearings and the distance to the landmark over time.
namespace calib {

PlotFiles BearingCalibrationPlots(const BearingLog& log, const BearingCalibrationResult& result);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_BEARING_CALIBRATION_PLOTS_H_
