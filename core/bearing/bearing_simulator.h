#ifndef CALIB_CORE_BEARING_BEARING_SIMULATOR_H_
#define CALIB_CORE_BEARING_BEARING_SIMULATOR_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/se2.h>
#include <calib/core/timing/logging_model.h>

#include <cstdint>
#include <functional>
#include <vector>

// Simulated bearing logs with known truth (Martinelli 2009, §8.1): the robot follows eqs. 1–2
// exactly (wheel speeds constant within each integration step, so circles are exact circles),
// the encoders report each step's wheel rotation Δα with variance K²/r·|Δα|, and the sensor
// reports the landmark's bearing (eq. 6) with Gaussian noise.
namespace calib {

// Nominal wheel speeds (m/s, wheel travel = r × rotation).
struct WheelSpeeds {
  double left_mps = 0.0;
  double right_mps = 0.0;
};

struct BearingRunSpec {
  int id = 0;               // 0: the run's index + 1.
  double q = 0.0;           // Circular run: vR = ν, vL = q·ν.
  double loops = 1.0;       // Length of a circular run in turns of the robot (2π/|ξq| of s each).
  double duration_s = 0.0;  // > 0: overrides `loops`; required with `wheel_speeds`.
  Pose2d world_T_robot_start = Pose2d(0.0, -1.0, 0.0);  // Landmark 1 m to the left.
  // Any smooth trajectory: nominal wheel speeds at time t from the run's start. Empty: a circle.
  std::function<WheelSpeeds(double t_s)> wheel_speeds;
};

struct BearingSimOptions {
  double wheel_radius_m = 0.3;          // Nominal r (Table 1).
  double wheelbase_m = 0.5;             // Nominal B.
  double right_wheel_speed_mps = 0.05;  // ν.
  double encoder_rate_hz = 50.0;
  int integration_substeps = 1;    // Integration steps per encoder period.
  double encoder_noise_k = 0.001;  // K (m^½): Δα read with variance K²/r·|Δα|; 0: exact.
  double bearing_rate_hz = 1.0;
  double bearing_noise_rad = 0.0;  // σβ.
  double start_time_s = 0.0;       // Clock value at the start of the first run.
  // A bearing stamped t was taken at t + time_offset_s on the odometry clock (the contract's
  // `time_offset`); the robot stands still before its run starts and after it ends.
  double time_offset_s = 0.0;
  double gap_between_runs_s = 10.0;
  BearingMetricParams truth{0.0, 0.3, M_PI / 2.0, 0.99, 1.006, 0.97};  // Table 2.
  std::vector<BearingRunSpec> runs;  // Empty: Martinelli's q = 0.9, 0, −1, one loop each.
  int initial_distance_run = 0;      // A run id: meta.initial_distance gets its true D0; 0: none.
  uint64_t seed = 1;
  // Bearings and encoders as a real robot logs them, per run from its start: a free-running
  // sensor (its sample grid replaces bearing_rate_hz), a logger stamping the latest bearing at
  // its pick-up, encoder polls every encoder_period_s (replacing encoder_rate_hz) at scattered
  // true times with scattered stamps, repeated rows. All zero: the plain log, unchanged. Its
  // random draws come from streams of their own, so the motion and the noise stay the same.
  LoggingModel logging;
};

struct BearingRunTruth {
  int id = 0;
  double q = 0.0;
  bool circular = false;
  Pose2d world_T_robot_start = Pose2d::Zero();
  double initial_distance_m = 0.0;
  BearingCircle circle;  // Circular runs: the noise-free observation function, node in [0, π/|ξq|).
  double xi_q_per_m = 0.0;
  double eta_q_per_m = 0.0;
  double mu0 = 0.0, gamma0_rad = 0.0;             // Eq. 3 at the start.
  CircularState<double> state0{0.0, 0.0, 0.0};    // A0, V0, L (eq. 15) at the start.
  double k_per_m = 0.0;                           // Eq. 17.
  double c_rad = 0.0;                             // Eq. 21.
  std::vector<Pose2d> world_T_robot_at_bearings;  // True poses at the bearing times (per row).
  LoggedTimingTruth timing;  // Per written row, the true time (from the run's start, + offset).
};

struct BearingSimTruth {
  BearingMetricParams metric;
  BearingParams params;
  std::vector<BearingRunTruth> runs;
};

// The runs of Martinelli's §8.1: q = 0.9, 0, −1, one loop each, from `start`.
std::vector<BearingRunSpec> MartinelliRuns(const Pose2d& world_T_robot_start = Pose2d(0, -1, 0));

// A run at constant nominal speed whose turn rate swings sinusoidally: wheel speeds
// speed·(1 ∓ swing·sin(2πt/period)), so ω = 2·speed·swing/B·sin(2πt/period) (nominal). Its
// curvature varies (the calibration is observable) while v stays constant.
BearingRunSpec WeavingRun(double duration_s = 300.0, double period_s = 80.0, double swing = 0.9,
                          double speed_mps = 0.05,
                          const Pose2d& world_T_robot_start = Pose2d(0.0, -1.0, 0.0));

BearingLog SimulateBearingLog(const BearingSimOptions& options, BearingSimTruth* truth = nullptr);

}  // namespace calib

#endif  // CALIB_CORE_BEARING_BEARING_SIMULATOR_H_
