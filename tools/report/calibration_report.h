#ifndef CALIB_TOOLS_REPORT_CALIBRATION_REPORT_H_
#define CALIB_TOOLS_REPORT_CALIBRATION_REPORT_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/diff_drive.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/timing/stamp_timing.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_model_screen.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>
#include <calib/solvers/timing/laser_timing_calibration.h>

#include <functional>
#include <future>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

// The report of `calib calibrate` (its JSON, summary and verdict), assembled in one place for
// the command line and the Python module: the result's JSON, the timing, the recording, the
// model screen, the odometry drift, the verdict.
namespace calib {

struct CalibrationReport {
  nlohmann::ordered_json json;
  std::string summary;
  // The laser calibration reported (the scan-point refinement's when it ran).
  LaserCalibrationResult laser;
};

struct LaserReportOptions {
  std::string input, loss = "cauchy";
  std::optional<OdometryParams> nominal;  // The driver's wheels, when known.
  LaserCalibrationOptions screen;         // The calibration options the model screen reuses.
  bool screen_model = true;
  int screen_max_intervals = 50000;  // Longer logs are not screened (say so; diagnose them).
  bool scan_points = false;          // The refinement on the scan points was asked for (bags).
  // The screen started beside the calibration (StartLaserModelScreen); when not valid, the report
  // runs it.
  std::shared_future<StatusOr<LaserModelScreen>> started_screen;
  // When valid, the screen started beside the calibration waits for the calibration's closed
  // forms (ScreenClosedForms) instead of computing them again.
  std::shared_future<std::shared_ptr<const LaserCalibrationResult>> calibration_closed_forms;
};

// Hands the calibration's closed forms (its consensus screen's and the seed) to the model screen
// started beside it. Give() them once the calibration has them (its options' closed_forms_done:
// Giver()); destroyed without, it releases the screen with none, which then computes its own.
// Destroy it before the screen's future is waited for: declare it after the report options.
class ScreenClosedForms {
 public:
  ScreenClosedForms() : future_(promise_.get_future().share()) {}
  ~ScreenClosedForms() {
    if (!given_) promise_.set_value(nullptr);
  }
  ScreenClosedForms(const ScreenClosedForms&) = delete;
  ScreenClosedForms& operator=(const ScreenClosedForms&) = delete;

  void Give(const LaserCalibrationResult& result) {
    if (given_) return;
    given_ = true;
    promise_.set_value(std::make_shared<const LaserCalibrationResult>(result));
  }
  std::function<void(const LaserCalibrationResult&)> Giver() {
    return [this](const LaserCalibrationResult& result) { Give(result); };
  }
  std::shared_future<std::shared_ptr<const LaserCalibrationResult>> future() const {
    return future_;
  }

 private:
  std::promise<std::shared_ptr<const LaserCalibrationResult>> promise_;
  std::shared_future<std::shared_ptr<const LaserCalibrationResult>> future_;
  bool given_ = false;  // On the calibration's thread only.
};

// Starts the model screen of a log of intervals on a second thread: it needs the log only, so it
// runs beside the calibration (on the real sets each takes about half of the time). Not valid when
// the report would not screen that log (screen off, or longer than screen_max_intervals).
// `intervals` must outlive the future.
std::shared_future<StatusOr<LaserModelScreen>> StartLaserModelScreen(
    const std::vector<LaserInterval>& intervals, const LaserReportOptions& options);

// A calibration of intervals (tuples, CSV, streams with --timing off); `logs`: the logs it was
// calibrated from (the screen runs on a single log only).
CalibrationReport LaserIntervalReport(const LaserCalibrationResult& result,
                                      const std::vector<const LaserLog*>& logs,
                                      const LaserReportOptions& options);

// A timing-aware calibration of raw streams, or of a bag (`bag`, may be null).
CalibrationReport LaserTimingReport(const LaserTimingResult& result, const LaserLog& log,
                                    const RobotBagCalibration* bag,
                                    const LaserReportOptions& options);

CalibrationReport BearingCalibrationReport(const BearingCalibrationResult& result,
                                           const BearingLog& log, const std::string& input,
                                           const std::string& loss);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_CALIBRATION_REPORT_H_
