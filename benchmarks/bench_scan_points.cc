// The two routes from raw scans to a calibration side by side on the simulator's robots: match
// then calibrate (two-stage), and the refinement against the scan points. Per scenario and route:
// how often each parameter falls within 2σ of the truth, the largest mean z (a bias shows), the
// RMS of z, and how much smaller the scan points' σ are.
#include <calib/core/scan/scan_simulator.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "benchmarks/bench_sections.h"

namespace calib::bench {
namespace {

struct Scenario {
  std::string name;
  int scans = 600, beams = 360;
  double fov_deg = 360.0, scan_period_s = 0.1, max_wheel_speed = 5.0;
  WorldKind world = WorldKind::kMixed;
  bool upside_down = false;
  // The nominal wheels (2 % off the truth) given, as from the robot's configuration: the matcher
  // is seeded by them, and the scan points can start from them without the two-stage route.
  bool nominal_wheels = false;
};

ScanSimOptions Robot(const Scenario& s, uint64_t seed) {
  ScanSimOptions o;
  o.laser = DefaultScanLaserOptions();
  o.laser.num_intervals = s.scans - 1;
  o.laser.mean_interval_s = s.scan_period_s;
  o.laser.max_wheel_speed = s.max_wheel_speed;
  o.laser.seed = seed;
  o.beams = s.beams;
  o.field_of_view_rad = s.fov_deg * M_PI / 180.0;
  o.range_noise_sigma_m = 0.01;
  o.missing_probability = 0.02;
  o.sweep_s = s.scan_period_s;  // The sweep lasts the whole period, as a spinning lidar's does.
  o.encoder_rate_hz = 50.0;
  o.world.kind = s.world;
  o.upside_down = s.upside_down;
  o.seed = seed;
  return o;
}

struct RouteStats {
  LaserParamVector sum_z = LaserParamVector::Zero(), sum_z2 = LaserParamVector::Zero();
  int within = 0, runs = 0;
  double seconds = 0.0;

  void Add(const LaserParamVector& z, double s) {
    sum_z += z;
    sum_z2 += z.cwiseProduct(z);
    for (int p = 0; p < kNumLaserParams; ++p) within += std::abs(z(p)) <= 2.0;
    ++runs;
    seconds += s;
  }
  nlohmann::ordered_json Print(const char* route) const {
    const int n = std::max(1, runs);
    const LaserParamVector mean = sum_z / n;
    int worst = 0;
    mean.cwiseAbs().maxCoeff(&worst);
    const double coverage = 100.0 * within / (kNumLaserParams * n);
    const double rms = std::sqrt(sum_z2.sum() / (kNumLaserParams * n));
    std::printf(
        "    %-12s %2d runs, %.1f s each: within 2σ %3.0f %%, RMS z %.2f, largest mean z %+.2f "
        "(%s)\n",
        route, runs, seconds / n, coverage, rms, mean(worst), kLaserParamNames[worst].c_str());
    return {{"runs", runs},
            {"seconds_each", seconds / n},
            {"within_2_sigma", coverage / 100.0},
            {"rms_z", rms},
            {"largest_mean_z", mean(worst)},
            {"largest_mean_z_parameter", kLaserParamNames[worst]}};
  }
};

LaserParamVector Z(const LaserCalibration& estimate, const LaserParamVector& stddev,
                   const ScanSimTruth& truth) {
  LaserCalibration t;
  t.odometry = truth.odometry;
  t.base_T_sensor = truth.base_T_sensor;
  return (estimate.ToVector() - t.ToVector()).cwiseQuotient(stddev);
}

nlohmann::ordered_json CompareRoutes(const Scenario& s, int seeds) {
  RouteStats two_stage, scan_points;
  double log_sigma_ratio = 0.0;
  int failed = 0, refused = 0;  // refused: the two-stage route could not calibrate.
  for (int seed = 1; seed <= seeds; ++seed) {
    const StatusOr<ScanSimulation> sim = SimulateScans(Robot(s, seed));
    if (!sim.ok()) {
      ++failed;
      continue;
    }
    RobotMessages bag = ScanSimulationMessages(*sim);
    bag.source = s.name;
    RobotBagOptions options;
    options.scan_points = ScanPointOptions();
    if (s.nominal_wheels) {
      const OdometryParams& wheels = sim->truth.odometry;
      options.nominal_wheel_radius_m = 1.02 * 0.5 * (wheels.left_radius_m + wheels.right_radius_m);
      options.nominal_wheelbase_m = 0.98 * wheels.wheelbase_m;
    }
    const Stopwatch clock;
    const StatusOr<RobotBagCalibration> r =
        CalibrateRobotMessages(bag, options, LaserTimingOptions());
    const double seconds = clock.Seconds();
    if (!r.ok() || !r->scan_points) {
      ++failed;
      continue;
    }
    const LaserCalibrationResult& c = r->result.calibration;
    const double refine_s = r->scan_points->seconds;
    scan_points.Add(Z(r->scan_points->estimate, r->scan_points->stddev, sim->truth), refine_s);
    if (!r->two_stage_failed.empty()) {  // The scan points alone: nothing to compare with.
      ++refused;
      continue;
    }
    two_stage.Add(Z(c.estimate, c.stddev, sim->truth), seconds - refine_s);
    log_sigma_ratio += (r->scan_points->stddev.array() / c.stddev.array()).log().mean();
  }
  const double ratio = std::exp(log_sigma_ratio / std::max(1, two_stage.runs));
  std::printf("  %s (%d scans of %d beams over %.0f°, %.0f Hz, wheels up to %.1f rad/s%s%s):\n",
              s.name.c_str(), s.scans, s.beams, s.fov_deg, 1.0 / s.scan_period_s, s.max_wheel_speed,
              s.upside_down ? ", lidar upside down" : "",
              s.nominal_wheels ? ", nominal wheels given" : "");
  nlohmann::ordered_json row = {
      {"scenario", s.name}, {"seeds", seeds}, {"failed", failed}, {"two_stage_refused", refused}};
  row["two_stage"] = two_stage.Print("two-stage");
  row["scan_points"] = scan_points.Print("scan points");
  if (refused > 0) {
    std::printf(
        "    the two-stage route refused %d run(s) (too few usable matches): there the scan "
        "points calibrated alone, from the nominal wheels\n",
        refused);
  }
  const std::string failures = failed ? ", " + std::to_string(failed) + " run(s) failed" : "";
  if (two_stage.runs > 0) {
    std::printf("    σ of the scan points / σ of the two-stage (geometric mean): %.2f%s\n", ratio,
                failures.c_str());
    row["sigma_ratio"] = ratio;
  } else if (failed) {
    std::printf("    %s\n", failures.substr(2).c_str());
  }
  return row;
}

}  // namespace

nlohmann::ordered_json RunScanPointComparison(const BenchConfig& config) {
  const int seeds = config.seeds > 0 ? config.seeds : (config.quick ? 2 : 10);
  std::printf(
      "Two-stage (match, then calibrate) against the refinement on the scan points, %d "
      "seeds, sweeps of the whole period, range noise 1 cm:\n",
      seeds);
  std::vector<Scenario> scenarios(6);
  scenarios[0].name = "baseline";
  scenarios[1].name = "fast turns";
  scenarios[1].max_wheel_speed = 12.0;
  scenarios[2].name = "long sweeps";
  scenarios[2].scan_period_s = 0.2;
  scenarios[2].scans = 300;
  scenarios[3].name = "corridor";
  scenarios[3].world = WorldKind::kCorridor;
  scenarios[3].nominal_wheels = true;
  scenarios[4].name = "dense 270°";
  scenarios[4].beams = 1081;
  scenarios[4].fov_deg = 270.0;
  // The baseline's robot with its lidar upside down (tf says so): mirrored and de-skewed.
  scenarios[5].name = "upside down";
  scenarios[5].upside_down = true;
  nlohmann::ordered_json out;
  for (const Scenario& s : scenarios) out.push_back(CompareRoutes(s, seeds));
  return out;
}

}  // namespace calib::bench
