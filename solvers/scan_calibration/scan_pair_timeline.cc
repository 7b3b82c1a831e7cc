#include <calib/core/timing/encoder_integration.h>
#include <calib/solvers/scan_calibration/scan_pair_timeline.h>

#include <algorithm>

namespace calib {

void PairTimeline::Locate(double t_s, int* step, double* fraction) const {
  const int last = static_cast<int>(steps.size());
  if (!(t_s > knot_time_s.front())) {
    *step = 0;
    *fraction = 0.0;
    return;
  }
  if (!(t_s < knot_time_s.back())) {
    *step = last;
    *fraction = 0.0;
    return;
  }
  const auto after = std::upper_bound(knot_time_s.begin(), knot_time_s.end(), t_s);
  *step = static_cast<int>(after - knot_time_s.begin()) - 1;
  const double t0 = knot_time_s[*step];
  *fraction = (t_s - t0) / (*after - t0);
}

PairTimeline MakePairTimeline(const std::vector<EncoderSample>& encoders, double t0_s,
                              double t_end_s) {
  PairTimeline out;
  out.knot_time_s.push_back(t0_s);
  auto it = std::upper_bound(encoders.begin(), encoders.end(), t0_s,
                             [](double t, const EncoderSample& e) { return t < e.t_s; });
  for (; it != encoders.end() && it->t_s < t_end_s; ++it) out.knot_time_s.push_back(it->t_s);
  out.knot_time_s.push_back(t_end_s);
  double left = 0.0, right = 0.0;
  InterpolateWheelAngles(encoders, t0_s, &left, &right);
  for (size_t k = 1; k < out.knot_time_s.size(); ++k) {
    double next_left = 0.0, next_right = 0.0;
    InterpolateWheelAngles(encoders, out.knot_time_s[k], &next_left, &next_right);
    out.steps.push_back(WheelStep{out.knot_time_s[k] - out.knot_time_s[k - 1], next_left - left,
                                  next_right - right});
    left = next_left;
    right = next_right;
  }
  return out;
}

std::vector<Pose2d> KnotPoses(const PairTimeline& timeline, const OdometryParams& p) {
  std::vector<Pose2d> poses(timeline.steps.size() + 1, Pose2d::Zero());
  for (size_t s = 0; s < timeline.steps.size(); ++s) {
    const WheelStep& step = timeline.steps[s];
    poses[s + 1] =
        Compose(poses[s], WheelStepDisplacement(p.left_radius_m, p.right_radius_m, p.wheelbase_m,
                                                step.left_rad, step.right_rad));
  }
  return poses;
}

Pose2d LaserMotion(const PairTimeline& timeline, const std::vector<Pose2d>& knot_poses,
                   const LaserCalibration& c, double t_s) {
  int step = 0;
  double fraction = 0.0;
  timeline.Locate(t_s, &step, &fraction);
  Pose2d base = knot_poses[step];
  if (fraction > 0.0) {
    const WheelStep& s = timeline.steps[step];
    const OdometryParams& p = c.odometry;
    base = Compose(base, WheelStepDisplacement(p.left_radius_m, p.right_radius_m, p.wheelbase_m,
                                               fraction * s.left_rad, fraction * s.right_rad));
  }
  return SensorMotionFromRobotMotion(c.base_T_sensor, base);
}

}  // namespace calib
