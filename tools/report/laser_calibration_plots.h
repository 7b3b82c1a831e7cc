#ifndef CALIB_TOOLS_REPORT_LASER_CALIBRATION_PLOTS_H_
#define CALIB_TOOLS_REPORT_LASER_CALIBRATION_PLOTS_H_

#include <calib/core/laser/laser_log.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <calib/tools/report/svg_plot.h>

#include <optional>
#include <string>
#include <vector>

// The plots of `calib calibrate --plots_dir` for the laser–odometry problem, per log:
//   laser_paths.svg      the sensor's path from scan matching against dead reckoning with the
//                        "before" parameters and the calibrated ones, and how far each strays;
//   laser_residuals.svg  histograms of the scan-matching residual (x, y, θ) with the fitted
//                        noise σ, rejected intervals apart;
//   laser_coverage.svg   each interval's (v, ω), used and rejected.
// Several logs calibrated jointly: one set per log, named log1_..., log2_....
namespace calib {

// The wheels the calibration is compared with: the driver's nominal ones when known (their
// mounting is the calibrated one), else the closed-form seed.
struct LaserPlotBaseline {
  double nominal_wheel_radius_m = 0.0, nominal_wheelbase_m = 0.0;  // 0: not known.
};

PlotFiles LaserCalibrationPlots(const std::vector<const std::vector<LaserInterval>*>& logs,
                                const LaserCalibrationResult& result,
                                const LaserPlotBaseline& baseline = {});

// A timing-aware calibration (raw streams, a robot's bag): the same plots on the intervals
// between the estimated sample times, where its residuals and noise σ live (the stamped
// intervals of `log` when those cannot be rebuilt). `calibration`: the result reported.
PlotFiles LaserTimingCalibrationPlots(const LaserLog& log, const LaserTimingResult& timing,
                                      const LaserCalibrationResult& calibration,
                                      const LaserPlotBaseline& baseline = {});

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_LASER_CALIBRATION_PLOTS_H_
