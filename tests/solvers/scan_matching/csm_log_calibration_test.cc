#include <calib/core/scan/csm_log.h>
#include <calib/core/scan/scan_simulator.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace calib {
namespace {

// A robot like Censi et al.'s: a Khepera III (20.6 mm wheels, 88 mm apart, up to 0.1 m/s) with a
// Hokuyo URG-04LX (681 beams over 240°, 4 m, 1 cm noise) turned by −90°, 10 scans a second, the
// encoders read with each scan.
ScanSimOptions Khepera(uint64_t seed) {
  ScanSimOptions o;
  o.laser = DefaultScanLaserOptions();
  o.laser.odometry = OdometryParams{0.0206, 0.0207, 0.088};
  o.laser.base_T_sensor = Pose2d(-0.0026, 0.0059, -1.558);
  o.laser.num_intervals = 599;
  o.laser.max_wheel_speed = 5.0;
  o.laser.seed = o.seed = o.world.seed = seed;
  o.beams = 681;
  o.field_of_view_rad = 240.0 * M_PI / 180.0;
  o.range_max_m = 4.0;
  o.range_noise_sigma_m = 0.01;
  o.missing_probability = 0.02;
  o.encoder_rate_hz = 0.0;
  return o;
}

// Written as the authors' raw log (scans with the encoders' counts, 2764.8 a turn), read back and
// calibrated from the scans: every parameter within 3σ of the truth.
TEST(CsmLogCalibration, ARawLogLikeCensisIsCalibratedFromItsScans) {
  const StatusOr<ScanSimulation> sim = SimulateScans(Khepera(4));
  ASSERT_TRUE(sim.ok()) << sim.message();
  const std::string text =
      CsmLogText(sim->scans, sim->encoders, kCensiKheperaCountsPerTurn, 1.2e9);
  const StatusOr<RobotMessages> bag = ReadCsmLogText(text, "log.log");
  ASSERT_TRUE(bag.ok()) << bag.message();
  const StatusOr<RobotBagCalibration> r =
      CalibrateRobotMessages(*bag, RobotBagOptions(), LaserTimingOptions());
  ASSERT_TRUE(r.ok()) << r.message();
  EXPECT_NE(r->log.wheel_source.find("2764.8 counts a turn"), std::string::npos)
      << r->log.wheel_source;
  LaserCalibration truth;
  truth.odometry = sim->truth.odometry;
  truth.base_T_sensor = sim->truth.base_T_sensor;
  const LaserCalibrationResult& c = r->result.calibration;
  const LaserParamVector z = (c.estimate.ToVector() - truth.ToVector()).cwiseQuotient(c.stddev);
  std::printf("z %+.2f %+.2f %+.2f %+.2f %+.2f %+.2f, σ r_l %.3f mm, b %.3f mm\n", z(0), z(1),
              z(2), z(3), z(4), z(5), 1e3 * c.stddev(0), 1e3 * c.stddev(2));
  EXPECT_LE(z.cwiseAbs().maxCoeff(), 3.0);
  for (const std::string& w : r->log.warnings) std::printf("warning: %s\n", w.c_str());

  // Another robot's counts: --ticks_per_rev's unit replaces the Khepera's.
  RobotBagOptions other;
  other.wheel_radians_per_unit = 2.0 * M_PI / 4096.0;
  const StatusOr<RobotBagLog> log = LaserLogFromRobotMessages(*bag, other);
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_NE(log->wheel_source.find("4096 counts a turn)"), std::string::npos) << log->wheel_source;
}

// Two experiments of the robot joined (the second's clock and counters restarted): the matching
// starts again at the join without calling it a lost track, and the calibration is within 3σ.
TEST(CsmLogCalibration, ExperimentsJoinedAreCalibratedTogether) {
  std::vector<RobotMessages> logs;
  ScanSimTruth truth;
  for (const uint64_t seed : {5, 6}) {
    const StatusOr<ScanSimulation> sim = SimulateScans(Khepera(seed));
    ASSERT_TRUE(sim.ok()) << sim.message();
    truth = sim->truth;
    const StatusOr<RobotMessages> log = ReadCsmLogText(
        CsmLogText(sim->scans, sim->encoders, kCensiKheperaCountsPerTurn, 1.2e9), "exp");
    ASSERT_TRUE(log.ok()) << log.message();
    logs.push_back(*log);
  }
  const StatusOr<RobotMessages> joined = JoinCsmLogs(std::move(logs), "l90");
  ASSERT_TRUE(joined.ok()) << joined.message();
  const StatusOr<RobotBagCalibration> r =
      CalibrateRobotMessages(*joined, RobotBagOptions(), LaserTimingOptions());
  ASSERT_TRUE(r.ok()) << r.message();
  EXPECT_EQ(r->log.scans.segments, 2);
  for (const auto* list : {&r->log.warnings, &r->log.scans.warnings}) {
    for (const std::string& w : *list) EXPECT_EQ(w.find("lost its track"), std::string::npos) << w;
  }
  LaserCalibration t;
  t.odometry = truth.odometry;
  t.base_T_sensor = truth.base_T_sensor;
  const LaserCalibrationResult& c = r->result.calibration;
  const LaserParamVector z = (c.estimate.ToVector() - t.ToVector()).cwiseQuotient(c.stddev);
  std::printf("z %+.2f %+.2f %+.2f %+.2f %+.2f %+.2f\n", z(0), z(1), z(2), z(3), z(4), z(5));
  EXPECT_LE(z.cwiseAbs().maxCoeff(), 3.0);
}

}  // namespace
}  // namespace calib
