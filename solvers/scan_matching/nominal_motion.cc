#include <calib/core/timing/encoder_integration.h>
#include <calib/solvers/scan_matching/nominal_motion.h>

#include <algorithm>

namespace calib {

bool WheelsAndMounting::known() const {
  return wheels.left_radius_m > 0.0 && wheels.right_radius_m > 0.0 && wheels.wheelbase_m > 0.0;
}

Pose2d SensorMotionBetween(const std::vector<EncoderSample>& encoders, double from_s, double to_s,
                           const WheelsAndMounting& robot) {
  double left[2], right[2];
  InterpolateWheelAngles(encoders, from_s, &left[0], &right[0]);
  InterpolateWheelAngles(encoders, to_s, &left[1], &right[1]);
  const OdometryParams& p = robot.wheels;
  const Pose2d base = WheelStepDisplacement(p.left_radius_m, p.right_radius_m, p.wheelbase_m,
                                            left[1] - left[0], right[1] - right[0]);
  return SensorMotionFromRobotMotion(robot.base_T_sensor, base);
}

SweepMotion SweepMotionOver(const std::vector<EncoderSample>& encoders, double from_s,
                            double sweep_s, const WheelsAndMounting& robot) {
  const double first = encoders.front().t_s, last = encoders.back().t_s;
  const double min_step_s = 1e-6 * sweep_s;
  std::vector<double> knots{std::clamp(from_s, first, last)};
  const double to_s = std::clamp(from_s + sweep_s, first, last);
  auto it = std::upper_bound(encoders.begin(), encoders.end(), knots[0],
                             [](double t, const EncoderSample& e) { return t < e.t_s; });
  for (; it != encoders.end() && it->t_s < to_s; ++it) {
    if (it->t_s - knots.back() > min_step_s) knots.push_back(it->t_s);
  }
  if (to_s - knots.back() > min_step_s) knots.push_back(to_s);
  if (knots.size() < 2) {  // The whole sweep outside the span: its nearest encoder step.
    const size_t n = encoders.size();
    knots = knots[0] >= last ? std::vector<double>{encoders[n - 2].t_s, last}
                             : std::vector<double>{first, encoders[1].t_s};
  }
  SweepMotion sweep{{}, {}};
  for (size_t k = 0; k + 1 < knots.size(); ++k) {
    sweep.start_s.push_back(k == 0 ? 0.0 : knots[k] - from_s);
    sweep.velocity.push_back(Log(SensorMotionBetween(encoders, knots[k], knots[k + 1], robot)) /
                             (knots[k + 1] - knots[k]));
    // Repeated encoder stamps at the span's end: no velocity to go on with, none is assumed.
    if (!sweep.velocity.back().allFinite()) return SweepMotion::Constant(Twist2d::Zero());
  }
  return sweep;
}

}  // namespace calib
