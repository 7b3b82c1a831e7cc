#ifndef CALIB_CORE_SCAN_SCAN_SIMULATOR_H_
#define CALIB_CORE_SCAN_SCAN_SIMULATOR_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/diff_drive.h>
#include <calib/core/encoder_sample.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/core/scan/scan_world.h>
#include <calib/core/se2.h>
#include <calib/core/status.h>
#include <calib/core/timing/logging_model.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

// Raw range scans of a simulated differential-drive robot in a 2D world of walls, with the
// encoder stream and the truth. The motion is the laser simulator's (the same LaserSimOptions give
// the same wheel angles as SimulateLaserStreams); every beam is cast from the sensor pose at its
// own time, so the robot moves during a sweep.
namespace calib {

namespace scan_sim_internal {
struct PathData;
}

// The robot's true pose at any time on the odometry clock, world_T_base = identity at the first
// scan's true time. Exact up to the integrator's quadrature (about 1e-12 m).
class RobotPath {
 public:
  RobotPath() = default;
  explicit RobotPath(std::shared_ptr<const scan_sim_internal::PathData> data)
      : data_(std::move(data)) {}
  Pose2d WorldTBase(double t_s) const;
  // Many times at once, `times_s` non-decreasing (much faster than one by one).
  std::vector<Pose2d> WorldTBase(const std::vector<double>& times_s) const;

 private:
  std::shared_ptr<const scan_sim_internal::PathData> data_;
};

LaserSimOptions DefaultScanLaserOptions();  // 10 Hz scans of a 0.5 m/s robot, 101 scans.

struct ScanSimOptions;
// Two posts at ±135° (10° wide, 0.15 m) and a guard behind (20° wide, 0.25 m): 11 % of a full
// circle's beams on the robot's body.
void AddMastAndGuard(ScanSimOptions* options);

struct ScanSimOptions {
  // The motion and the scan times: one scan at each of the laser simulator's interval boundaries
  // (num_intervals + 1 scans, every mean_interval_s ± interval_jitter_s). effects.time_offset_s
  // delays the sweeps from their stamps. scan_noise_sigma and outliers are unused.
  LaserSimOptions laser = DefaultScanLaserOptions();
  // When set, the scans are stamped and picked as this logger does (SimulateLoggedLaserStreams):
  // a scan's stamp is its row's stamp, its beams are taken from the true sample time on.
  std::optional<LoggingModel> logging;
  WorldOptions world;
  int beams = 360;
  double field_of_view_rad = 2.0 * M_PI;  // Centred on the sensor's x axis.
  double range_min_m = 0.05;
  double range_max_m = 30.0;
  double range_noise_sigma_m = 0.0;
  double missing_probability = 0.0;  // Returns dropped at random.
  bool missing_as_nan = false;       // No return: NaN instead of +inf.
  double sweep_s = 0.0;              // time_increment = sweep / beams; 0: instantaneous.
  // The lidar is mounted upside down (its z axis down): the scans are its own, counter-clockwise
  // in its frame and so clockwise as seen from the base, and tf (ScanSimulationMessages) says so.
  // base_T_sensor is the pose of the upright frame it is mirrored into.
  bool upside_down = false;
  // Parts of the robot in the lidar's view (posts, a guard): beams between the angles (the
  // lidar's frame, rad) return from range_m, nearer than any wall.
  struct BodySector {
    double from_rad, to_rad, range_m;
  };
  std::vector<BodySector> body;
  double encoder_rate_hz = 100.0;  // Without a logging model; 0: encoders at the scan times.
  std::string frame_id = "laser";
  uint64_t seed = 1;  // Range noise, missing returns (the motion uses laser.seed).
};

struct ScanSimTruth {
  OdometryParams odometry;
  Pose2d base_T_sensor = Pose2d::Zero();
  LaserEffects effects;
  std::vector<double> sweep_start_s;   // Per scan: the true time of beam 0 (odometry clock).
  std::vector<Pose2d> world_T_sensor;  // Per scan, at sweep_start_s.
  RobotPath path;
  bool upside_down = false;  // The scans are an upside-down lidar's (ScanSimOptions).
};

struct ScanSimulation {
  std::vector<LaserScan> scans;
  std::vector<EncoderSample> encoders;  // Cumulative wheel angles.
  ScanWorld world;
  ScanSimTruth truth;
};

// Fails on bad options (the message names the field) or a world that cannot be built.
StatusOr<ScanSimulation> SimulateScans(const ScanSimOptions& options);

struct RobotMessageNames {
  double epoch_s = 1.7e9;  // Added to every time, so that stamps look like a real recording's.
  std::string scan_topic = "/scan", joint_topic = "/joint_states", odom_topic = "/odom";
  std::string odom_frame = "odom", base_frame = "base_link";
  std::string left_joint = "left_wheel_joint", right_joint = "right_wheel_joint";
};

// The simulated robot's recording as a bag would hold it: the scans, one JointState per encoder
// sample (cumulative wheel angles as positions), the driver's Odometry (the encoders dead-reckoned
// with the true parameters) and base_T_sensor on /tf_static. Log times equal the stamps.
RobotMessages ScanSimulationMessages(const ScanSimulation& simulation,
                                     const RobotMessageNames& names = {});

}  // namespace calib

#endif  // CALIB_CORE_SCAN_SCAN_SIMULATOR_H_
