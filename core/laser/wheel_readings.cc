#include <calib/core/laser/wheel_readings.h>
#include <calib/core/text_number.h>

#include <cmath>

namespace calib {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

int UnwrapWheelAngles(std::vector<double>* values, size_t stride, size_t column) {
  const size_t n = stride == 0 ? 0 : values->size() / stride;
  if (n < 2) return 0;
  const auto at = [&](size_t k) -> double& { return (*values)[k * stride + column]; };
  constexpr double kSlack = 1e-6;
  bool signed_range = true, positive_range = true, jumps = false;
  for (size_t k = 0; k < n; ++k) {
    const double a = at(k);
    signed_range = signed_range && std::abs(a) <= kPi + kSlack;
    positive_range = positive_range && a >= -kSlack && a <= 2.0 * kPi + kSlack;
    if (k > 0) jumps = jumps || std::abs(a - at(k - 1)) > kPi;
  }
  if (!(signed_range || positive_range) || !jumps) return 0;
  int turns = 0;
  double offset = 0.0, previous = at(0);
  for (size_t k = 0; k < n; ++k) {
    const double raw = at(k);
    const double step = raw - previous;
    if (step > kPi) offset -= 2.0 * kPi, ++turns;
    if (step < -kPi) offset += 2.0 * kPi, ++turns;
    previous = raw;
    at(k) = raw + offset;
  }
  return turns;
}

Status ScaleWheelReadings(double radians_per_unit, LaserLog* log) {
  if (!(radians_per_unit > 0.0) || !std::isfinite(radians_per_unit)) {
    return Status::InvalidInput("radians per wheel-reading unit must be positive, got " +
                                Num(radians_per_unit));
  }
  for (LaserInterval& interval : log->intervals) {
    interval.left_speed *= radians_per_unit;
    interval.right_speed *= radians_per_unit;
    for (WheelStep& step : interval.steps) {
      step.left_rad *= radians_per_unit;
      step.right_rad *= radians_per_unit;
    }
  }
  for (EncoderSample& sample : log->streams.odometry) {
    sample.left_rad *= radians_per_unit;
    sample.right_rad *= radians_per_unit;
  }
  return Status::Ok();
}

Status ConvertWheelTicks(double ticks_per_rev, LaserLog* log) {
  if (!(ticks_per_rev > 0.0) || !std::isfinite(ticks_per_rev)) {
    return Status::InvalidInput("ticks per wheel turn must be positive, got " + Num(ticks_per_rev));
  }
  return ScaleWheelReadings(2.0 * kPi / ticks_per_rev, log);
}

}  // namespace calib
