// A TurtleBot3 Burger's LDS-01 as drivers misstate its beams' timing, the calibration trusting
// the driver against checking the timing on the sweeps' seams (solvers/scan_matching/beam_timing):
// per misstatement and route, how often each parameter falls within 2σ of the truth and the
// largest mean z; for the check, how often it found the true timing.
#include <calib/core/scan/scan_simulator.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "benchmarks/bench_sections.h"

namespace calib::bench {
namespace {

struct Misstatement {
  const char* name;
  bool reversed;  // Beams listed against the order they were measured in.
  double scale;   // The driver's time_increment over the true one.
};

// 33 mm wheels 160 mm apart up to 0.22 m/s and 2.8 rad/s; the LDS-01 at 5 Hz, 360 beams,
// 0.12–3.5 m, 1 cm of range noise, 5 % of the returns missing.
ScanSimOptions Burger(int scans, uint64_t seed) {
  ScanSimOptions o;
  o.laser = DefaultScanLaserOptions();
  o.laser.odometry = OdometryParams{0.033, 0.033, 0.160};
  o.laser.base_T_sensor = Pose2d(-0.032, 0.0, 0.0);
  o.laser.num_intervals = scans - 1;
  o.laser.mean_interval_s = 0.2;
  o.laser.max_wheel_speed = 6.67;
  o.laser.seed = seed;
  o.beams = 360;
  o.sweep_s = 0.2;
  o.range_min_m = 0.12;
  o.range_max_m = 3.5;
  o.range_noise_sigma_m = 0.01;
  o.missing_probability = 0.05;
  o.encoder_rate_hz = 30.0;
  o.seed = seed;
  return o;
}

void Misstate(const Misstatement& m, std::vector<LaserScan>* scans) {
  for (LaserScan& scan : *scans) {
    if (m.reversed) {
      scan.angle_min_rad += (scan.ranges_m.size() - 1.0) * scan.angle_increment_rad;
      scan.angle_increment_rad = -scan.angle_increment_rad;
      std::reverse(scan.ranges_m.begin(), scan.ranges_m.end());
    }
    scan.time_increment_s *= m.scale;
  }
}

struct Route {
  LaserParamVector sum_z = LaserParamVector::Zero();
  double worst_z = 0.0;  // The largest |z| of any run.
  int within = 0, runs = 0, found = 0;

  nlohmann::ordered_json Print(const char* name, bool checked) const {
    const int n = std::max(runs, 1);
    int worst = 0;
    const double largest = (sum_z / n).cwiseAbs().maxCoeff(&worst);
    const double coverage = 100.0 * within / (kNumLaserParams * n);
    std::printf(
        "    %-8s %2d runs: within 2σ %3.0f %%, largest |mean z| %5.2f (%s), largest |z| %5.1f",
        name, runs, coverage, largest, kLaserParamNames[worst].c_str(), worst_z);
    if (checked) std::printf(", true timing found %d of %d", found, runs);
    std::printf("\n");
    nlohmann::ordered_json row = {{"runs", runs},
                                  {"within_2_sigma", coverage / 100.0},
                                  {"largest_abs_mean_z", largest},
                                  {"largest_parameter", kLaserParamNames[worst]},
                                  {"largest_abs_z", worst_z}};
    if (checked) row["true_timing_found"] = found;
    return row;
  }
};

}  // namespace

nlohmann::ordered_json RunBeamTimingBench(const BenchConfig& config) {
  const int seeds = config.seeds > 0 ? config.seeds : (config.quick ? 1 : 5);
  const int scans = config.quick ? 300 : 600;
  std::printf(
      "Beam timing as drivers state it, a TurtleBot3 Burger's LDS-01 (5 Hz, 360 beams, %d scans, "
      "%d seeds), the driver trusted against checked on the sweeps' seams:\n",
      scans, seeds);
  const std::vector<Misstatement> cases = {{"true", false, 1.0},
                                           {"LDS-01 driver (reversed, 1/18)", true, 1.0 / 18.0},
                                           {"1/18 of the true increment", false, 1.0 / 18.0},
                                           {"reversed", true, 1.0},
                                           {"no beam times", false, 0.0}};
  nlohmann::ordered_json out;
  for (const Misstatement& m : cases) {
    Route trusted, checked;
    for (int seed = 1; seed <= seeds; ++seed) {
      const StatusOr<ScanSimulation> sim = SimulateScans(Burger(scans, seed));
      if (!sim.ok()) continue;
      RobotMessages bag = ScanSimulationMessages(*sim);
      bag.source = "burger";
      const double true_increment_s = bag.scans.begin()->second.front().time_increment_s;
      Misstate(m, &bag.scans.begin()->second);
      for (const bool check : {false, true}) {
        RobotBagOptions options;
        options.check_beam_timing = check;
        const StatusOr<RobotBagCalibration> r =
            CalibrateRobotMessages(bag, options, LaserTimingOptions());
        if (!r.ok()) continue;
        LaserCalibration truth;
        truth.odometry = sim->truth.odometry;
        truth.base_T_sensor = sim->truth.base_T_sensor;
        const LaserCalibrationResult& c = r->result.calibration;
        const LaserParamVector z =
            (c.estimate.ToVector() - truth.ToVector()).cwiseQuotient(c.stddev);
        Route& route = check ? checked : trusted;
        route.sum_z += z;
        route.worst_z = std::max(route.worst_z, z.cwiseAbs().maxCoeff());
        for (int p = 0; p < kNumLaserParams; ++p) route.within += std::abs(z(p)) <= 2.0;
        ++route.runs;
        const std::optional<BeamTimingCheck>& b = r->log.beam_timing;
        route.found +=
            b && b->chosen.reversed == m.reversed &&
            std::abs(b->chosen.time_increment_s - true_increment_s) < 0.01 * true_increment_s;
      }
    }
    std::printf("  %s:\n", m.name);
    out.push_back({{"misstatement", m.name},
                   {"trusted", trusted.Print("trusted", false)},
                   {"checked", checked.Print("checked", true)}});
  }
  return out;
}

}  // namespace calib::bench
