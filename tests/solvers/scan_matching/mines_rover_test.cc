#include <calib/core/scan/csm_log.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

// A real recording with raw encoder counts and raw scans: the Paris-Mines rover of CoreSLAM
// (data/real/mines_rover/README.md), calibrated from its own log and compared with two external
// references: the wheels that BreezySLAM's odometry-free SLAM trajectory of the same log implies
// (r and b), and the building's walls, whose direction the calibrated heading must keep (the
// radii's ratio, which drifts the heading on every straight, and r/b).
namespace calib {
namespace {

constexpr double kCountsPerTurn = 2000.0;
constexpr double kNominalWheelbaseM = 0.330;  // The authors' half-axle 165 mm, twice.

std::string DataPath(const std::string& name) {
  return std::string(CALIB_SOURCE_DIR) + "/data/real/mines_rover/" + name;
}

// One row of the reference trajectory: the line's time and counters, the SLAM's pose.
struct SlamPose {
  double t_s, left_rad, right_rad, x_m, y_m, theta_rad;
};

std::vector<SlamPose> ReadTrajectory(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // t_us,left_ticks,right_ticks,x_mm,y_mm,theta_deg
  std::vector<SlamPose> poses;
  while (std::getline(in, line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream fields(line);
    double t_us, left, right, x_mm, y_mm, theta_deg;
    if (!(fields >> t_us >> left >> right >> x_mm >> y_mm >> theta_deg)) continue;
    const double to_rad = 2.0 * M_PI / kCountsPerTurn;
    poses.push_back({1e-6 * t_us, to_rad * left, to_rad * right, 1e-3 * x_mm, 1e-3 * y_mm,
                     theta_deg * M_PI / 180.0});
  }
  return poses;
}

// A wheel angle at time t, linear between the lines' readings.
double WheelAt(const std::vector<SlamPose>& p, double t, bool left) {
  size_t i = 0;
  while (i + 2 < p.size() && p[i + 1].t_s <= t) ++i;
  const double w = (t - p[i].t_s) / (p[i + 1].t_s - p[i].t_s);
  const double a = left ? p[i].left_rad : p[i].right_rad;
  const double b = left ? p[i + 1].left_rad : p[i + 1].right_rad;
  return a + w * (b - a);
}

struct Fit {
  double slope = 0.0, stddev = 0.0, rms = 0.0;
};

// Least squares through the origin, with the slope's standard error from the residuals.
Fit FitThroughOrigin(const std::vector<double>& x, const std::vector<double>& y) {
  double sxx = 0.0, sxy = 0.0;
  for (size_t i = 0; i < x.size(); ++i) sxx += x[i] * x[i], sxy += x[i] * y[i];
  Fit f;
  f.slope = sxy / sxx;
  double ssr = 0.0;
  for (size_t i = 0; i < x.size(); ++i) ssr += std::pow(y[i] - f.slope * x[i], 2);
  f.rms = std::sqrt(ssr / x.size());
  f.stddev = std::sqrt(ssr / (x.size() - 1) / sxx);
  return f;
}

struct Reference {
  double shift_s, r_m, r_stddev_m, b_m, b_stddev_m, heading_rms_rad;
};

// Over windows of 10 scans, with the counters read `shift_s` after each scan's stamp: the SLAM's
// heading change against r/b·(Δφ_r − Δφ_l), and where it turned less than 3°, its distance against
// r·|Δφ_l + Δφ_r|/2 (rotation and straight travel are the same for any point of the robot).
Reference ReferenceAt(const std::vector<SlamPose>& p, double shift_s) {
  constexpr size_t kWindow = 10;
  std::vector<double> turn_x, turn_y, travel_x, travel_y;
  for (size_t k = 0; k + kWindow < p.size(); k += kWindow) {
    const SlamPose &a = p[k], &b = p[k + kWindow];
    if (a.t_s + shift_s < p.front().t_s + 0.3 || b.t_s + shift_s > p.back().t_s - 0.3) continue;
    const double dl = WheelAt(p, b.t_s + shift_s, true) - WheelAt(p, a.t_s + shift_s, true);
    const double dr = WheelAt(p, b.t_s + shift_s, false) - WheelAt(p, a.t_s + shift_s, false);
    const double turn = b.theta_rad - a.theta_rad;
    turn_x.push_back(dr - dl);
    turn_y.push_back(turn);
    if (std::abs(turn) < 3.0 * M_PI / 180.0) {
      travel_x.push_back(0.5 * std::abs(dl + dr));
      travel_y.push_back(std::hypot(b.x_m - a.x_m, b.y_m - a.y_m));
    }
  }
  const Fit r_over_b = FitThroughOrigin(turn_x, turn_y);
  const Fit r = FitThroughOrigin(travel_x, travel_y);
  const double b = r.slope / r_over_b.slope;
  return {shift_s,
          r.slope,
          r.stddev,
          b,
          b * std::hypot(r.stddev / r.slope, r_over_b.stddev / r_over_b.slope),
          r_over_b.rms};
}

// The shift (−0.3…0.3 s) whose heading fit leaves the least residual.
Reference BestReference(const std::vector<SlamPose>& p) {
  Reference best = ReferenceAt(p, 0.0);
  for (int i = -30; i <= 30; ++i) {
    const Reference r = ReferenceAt(p, 0.01 * i);
    if (r.heading_rms_rad < best.heading_rms_rad) best = r;
  }
  return best;
}

StatusOr<RobotBagCalibration> CalibrateLog(const std::string& name) {
  StatusOr<RobotMessages> bag = ReadCsmLog(DataPath(name));
  if (!bag.ok()) return bag.status();
  // calib calibrate --input NAME --ticks_per_rev 2000 --lidar_rotation_period 0.1
  for (auto& [topic, scans] : bag->scans) AssumeRotationPeriod(0.1, &scans);
  RobotBagOptions options;
  options.wheel_radians_per_unit = 2.0 * M_PI / kCountsPerTurn;
  return CalibrateRobotMessages(*bag, options, LaserTimingOptions());
}

class MinesRover : public testing::TestWithParam<const char*> {};

// Both calibrations agree with the reference within 3σ (their σ and the reference's together) on
// r_l, r_r and b, and find the scans' lag behind the counters that the reference finds; both put
// the wheelbase well short of the authors' nominal 330 mm, as the reference does.
TEST_P(MinesRover, AgreesWithTheSlamTrajectoryAndTheWalls) {
  const std::string log = GetParam();
  const Reference ref = BestReference(ReadTrajectory(DataPath(log + "_breezyslam.csv")));
  const StatusOr<RobotBagCalibration> r = CalibrateLog(log + ".log.bz2");
  ASSERT_TRUE(r.ok()) << r.message();
  const LaserCalibrationResult& c = r->result.calibration;
  const OdometryParams& o = c.estimate.odometry;
  std::printf(
      "%s: calib r_l %.2f ± %.2f, r_r %.2f ± %.2f, b %.1f ± %.1f mm, lag %.0f ms; "
      "reference (shift %.2f s) r %.2f ± %.2f, b %.1f ± %.1f mm\n",
      log.c_str(), 1e3 * o.left_radius_m, 1e3 * c.stddev(0), 1e3 * o.right_radius_m,
      1e3 * c.stddev(1), 1e3 * o.wheelbase_m, 1e3 * c.stddev(2), -1e3 * r->result.time_offset_s,
      ref.shift_s, 1e3 * ref.r_m, 1e3 * ref.r_stddev_m, 1e3 * ref.b_m, 1e3 * ref.b_stddev_m);
  for (const std::string& w : r->log.warnings) std::printf("  warning: %s\n", w.c_str());
  EXPECT_LE(std::abs(o.left_radius_m - ref.r_m), 3.0 * std::hypot(c.stddev(0), ref.r_stddev_m));
  EXPECT_LE(std::abs(o.right_radius_m - ref.r_m), 3.0 * std::hypot(c.stddev(1), ref.r_stddev_m));
  EXPECT_LE(std::abs(o.wheelbase_m - ref.b_m), 3.0 * std::hypot(c.stddev(2), ref.b_stddev_m));
  EXPECT_GT(kNominalWheelbaseM - o.wheelbase_m, 3.0 * c.stddev(2));
  EXPECT_GT(kNominalWheelbaseM - ref.b_m, 3.0 * ref.b_stddev_m);
  // The scans are older than the line's stamp, which is when the counters were read.
  EXPECT_NEAR(-r->result.time_offset_s, -ref.shift_s, 0.05);

  // Under the calibrated wheels' heading the building's walls keep their direction within the
  // calibration's own σ (and the trend's), and scatter less about it than under the nominal
  // wheels'.
  ASSERT_TRUE(r->log.walls.has_value());
  const WallCheck& walls = *r->log.walls;
  const StatusOr<RobotMessages> bag = ReadCsmLog(DataPath(log + ".log.bz2"));
  ASSERT_TRUE(bag.ok()) << bag.message();
  const WallCheck nominal =
      CheckAgainstWalls(bag->scans.at(kCsmScanTopic), false, r->log.scans.log.streams.odometry, o,
                        OdometryParams{0.077, 0.077, kNominalWheelbaseM}, r->result.time_offset_s);
  const WallHeading& h = walls.calibrated;
  const double deg = 180.0 / M_PI;
  std::printf(
      "walls under the calibrated wheels: drift %.1f ± %.1f° (calibration: ± %.1f°), "
      "scatter %.1f° (%d of %d scans); nominal: drift %.1f ± %.1f°, scatter %.1f°\n",
      deg * h.drift_rad, deg * h.drift_stddev_rad, deg * h.calibration_stddev_rad,
      deg * h.scatter_rad, walls.scans_with_walls, walls.scans, deg * nominal.nominal->drift_rad,
      deg * nominal.nominal->drift_stddev_rad, deg * nominal.nominal->scatter_rad);
  EXPECT_TRUE(walls.right_angled);
  EXPECT_GT(h.calibration_stddev_rad, 0.0);
  EXPECT_LE(std::abs(h.drift_rad), 3.0 * std::hypot(h.drift_stddev_rad, h.calibration_stddev_rad));
  EXPECT_LT(h.scatter_rad, nominal.nominal->scatter_rad);
}

INSTANTIATE_TEST_SUITE_P(Logs, MinesRover, testing::Values("exp1", "exp2"));

}  // namespace
}  // namespace calib
