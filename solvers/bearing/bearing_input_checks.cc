#include <calib/core/text_format.h>
#include <calib/solvers/bearing/bearing_input_checks.h>

#include <cmath>
#include <string>
#include <utility>

namespace calib {
namespace {

// Without a scale, radii that differ by more than this fraction call for the swapped reading.
constexpr double kUnequalRadii = 1.15;
// A reading is a robot when its corrections are within this factor of 1 (radii within 5 %).
constexpr double kRobotCorrection = 1.2;
constexpr double kRobotRadii = 1.05;

bool Within(double value, double factor) {
  return value > 0.0 && std::abs(std::log(value)) <= std::log(factor);
}

// A correction beyond [1/2, 2] and 3σ from 1 (with an initial distance), or unequal radii.
bool Implausible(const BearingCalibrationResult& r) {
  if (!r.has_metric) return !Within(r.estimate.delta, kUnequalRadii);
  const double values[3] = {r.metric.delta_r, r.metric.delta_l, r.metric.delta_b};
  for (int i = 0; i < 3; ++i) {
    const double sigma = r.metric_stddev(3 + i);
    if (!Within(values[i], 2.0) && std::abs(values[i] - 1.0) > 3.0 * sigma) return true;
  }
  return false;
}

bool Robot(const BearingCalibrationResult& r) {
  if (!Within(r.estimate.delta, kRobotRadii)) return false;
  return !r.has_metric ||
         (Within(r.metric.delta_r, kRobotCorrection) &&
          Within(r.metric.delta_l, kRobotCorrection) && Within(r.metric.delta_b, kRobotCorrection));
}

std::string Corrections(const BearingCalibrationResult& r) {
  if (!r.has_metric) return Format("radii in the ratio %.3g (δ = δL/δR)", r.estimate.delta);
  return Format("%.3g×, %.3g× and %.3g× (δR, δL, δB)", r.metric.delta_r, r.metric.delta_l,
                r.metric.delta_b);
}

// δR/δB = ξ·B far from 1: the wheel rotation (or meta.json) is in another unit.
Status CheckUnits(const BearingLog& log, double ratio, const std::string& where) {
  if (ratio >= 1.0 / 3.0 && ratio <= 3.0) return Status::Ok();
  std::string guess;
  if (std::abs(ratio / (M_PI / 180.0) - 1.0) < 0.1) {
    guess = "degrees (π/180 = 0.01745): convert them to radians";
  } else if (ratio < 1.0) {
    guess =
        Format("encoder ticks, about %.0f per wheel turn: convert them to radians (2π per turn)",
               2.0 * M_PI / ratio);
  } else {
    guess = "turns: convert them to radians (2π per turn)";
  }
  return Status::InvalidInput(
      where +
      Format("the calibrated wheels turn %.4g times as far as meta.json's wheel_radius %.4g m and "
             "wheelbase %.4g m say (δR/δB = ξ·B): odometry.csv's wheel rotation looks like ",
             ratio, log.meta.wheel_radius_m, log.meta.wheelbase_m) +
      guess + ", or meta.json's two lengths are not both in metres");
}

}  // namespace

Status SwappedOr(const BearingLog& log, const BearingCalibrationOptions& options,
                 const std::string& as_given, double bearing_sigma_rad, const Status& why) {
  BearingCalibrationOptions trial = options;
  trial.check_readings = false;
  trial.progress = nullptr;
  const StatusOr<BearingCalibrationResult> swapped =
      CalibrateBearing(WithWheelsSwapped(log), trial);
  if (!swapped.ok() || !Robot(*swapped) ||
      !(swapped->noise.bearing_sigma_rad <= 1.1 * bearing_sigma_rad)) {
    return why;
  }
  return Status::InvalidInput(
      (log.source.empty() ? "bearing log" : log.source) +
      ": odometry.csv's left and right wheel columns look swapped: as given, " + as_given +
      "; swapped, the calibrated wheels are " + Corrections(*swapped) +
      Format(" meta.json's, with the bearings fitted as well (σβ %.3g° against %.3g°); exchange "
             "the two columns",
             swapped->noise.bearing_sigma_rad * 180.0 / M_PI, bearing_sigma_rad * 180.0 / M_PI));
}

BearingLog WithWheelsSwapped(BearingLog log) {
  for (BearingRun& run : log.runs) {
    for (EncoderSample& s : run.odometry) std::swap(s.left_rad, s.right_rad);
  }
  return log;
}

Status CheckBearingReadings(const BearingLog& log, const BearingCalibrationOptions& options,
                            const BearingCalibrationResult& result) {
  const BearingParams& p = result.estimate;
  const std::string where = (log.source.empty() ? "bearing log" : log.source) + ": ";
  if (!(p.delta > 0.0)) {
    const char* wheel = p.xi_per_m > 0.0 ? "left" : "right";
    return Status::InvalidInput(
        where + "the " + wheel + " wheel's readings have the wrong sign: the calibration finds " +
        Format("the left wheel %.4g times the right one (δ = δL/δR); negate the %s column of ",
               p.delta, wheel) +
        "odometry.csv, so that positive wheel rotation drives the robot forward");
  }
  if (!(p.xi_per_m > 0.0)) {
    return Status::InvalidInput(
        where + "the robot turns the other way than its wheels say (the calibrated wheelbase " +
        Format("comes out negative: ξ = %.4g /m): both wheels' readings have the wrong sign, or ",
               p.xi_per_m) +
        "odometry.csv's left and right columns are swapped, or the bearings have the wrong sign "
        "(a camera mounted upside down)");
  }
  CALIB_RETURN_IF_ERROR(CheckUnits(log, p.xi_per_m * log.meta.wheelbase_m, where));
  if (!Implausible(result)) return Status::Ok();
  // Unequal wheels without a scale: only the swapped reading can say more.
  const Status implausible =
      !result.has_metric
          ? Status::Ok()
          : Status::InvalidInput(
                where + "the calibrated wheels are " + Corrections(result) +
                Format(" meta.json's wheel_radius %.4g m and wheelbase %.4g m: a robot's wheels "
                       "are within a few percent of their nominal size; check meta.json's values "
                       "and units, and that odometry.csv's left and right columns are the robot's "
                       "wheels, in radians",
                       log.meta.wheel_radius_m, log.meta.wheelbase_m));
  return SwappedOr(log, options,
                   "the calibrated wheels are " + Corrections(result) + " meta.json's",
                   result.noise.bearing_sigma_rad, implausible);
}

}  // namespace calib
