#ifndef CALIB_TOOLS_COMMANDS_COMMANDS_H_
#define CALIB_TOOLS_COMMANDS_COMMANDS_H_

#include <cstdint>
#include <optional>
#include <set>
#include <string>

// The calib commands. Each takes its options struct (filled from the flags in flags.cc, the only
// place that reads them), reads its input, calls the library, writes the report, and returns the
// process exit status: 0 on success, 1 with "calib: error: ..." on stderr otherwise.
namespace calib::cli {

// `calib calibrate`: a laser log (or several, comma-separated, calibrated jointly) or a bearing
// log directory.
struct CalibrateOptions {
  std::string input;
  std::string output;
  std::string format = "auto";  // Laser log format: auto, tuples, csv or stream.
  std::string loss = "cauchy";  // cauchy, huber, tukey or none.
  double loss_scale = 3.0;      // In whitened residual units.
  // Laser: the last passes under Tukey's biweight at this scale (0: none).
  double redescending_scale = 6.0;
  bool quiet = false;  // No summary on stdout, no progress on stderr.
  // Raw laser streams: auto (latent sample times, the clock model chosen by the data), stamps or
  // free_running (that model only), off (stamps taken as sample times).
  std::string timing = "auto";
  // A robot's bag: topics and joints (empty: picked when unique), the base frame (empty:
  // base_link, base_footprint), and the driver's nominal wheels (0: unknown; needed when the
  // wheel angles come from its odometry).
  std::string scan_topic, joint_state_topic, odom_topic, left_wheel_joint, right_wheel_joint;
  // A topic of the robot's own message with raw encoder counts, and its fields (empty: a known
  // type's).
  std::string encoder_topic, left_encoder_field, right_encoder_field;
  std::string base_frame;
  double nominal_wheel_radius = 0.0, nominal_wheelbase = 0.0;
  // The lidar's rotation period (s) for scans without beam times (time_increment 0); 0: none.
  double lidar_rotation_period_s = 0.0;
  std::string lidar_beam_timing = "auto";   // auto: checked against the scans; driver: trusted.
  std::string lidar_self_returns = "mask";  // mask: beams on the robot's body left out; keep.
  double lidar_min_range_m = 0.0;           // Ranges nearer are no return (0: the scans' own).
  std::string wheel_angle_unit = "rad";     // rad, deg, or ticks:N.
  double ticks_per_rev = 0.0;  // > 0: wheel readings are encoder ticks, this many per turn.
  bool scan_points = false;    // Refine against the scan points after the two-stage route.
  // A known sensor latency: a sample stamped t was taken at t + this (raw streams, bags, bearing
  // logs); empty: none given.
  std::optional<double> time_offset_s;
  std::string export_formats;  // --export: yaml, urdf, tf (comma-separated) or all; empty: none.
  // Plot folder: calibrate draws nothing when empty; diagnose then uses OUT_plots beside OUT.json.
  std::string plots_dir;
  std::string plot_format = "svg";  // svg, or png (each SVG also rasterized).
};
int RunCalibrate(const CalibrateOptions& options);

// `calib diagnose`: one log; the calibrate options plus the search's.
struct DiagnoseOptions : CalibrateOptions {
  double family_alpha = 0.01;  // Family-wise error rate of each forward step.
  int max_effects = 3;
  int cv_blocks = 5;                     // Contiguous held-out blocks.
  std::string candidates;                // Comma-separated laser effects; empty: all.
  std::string boundary_speeds = "auto";  // auto, piecewise or smooth (laser).
};
int RunDiagnose(const DiagnoseOptions& options);

// `calib simulate`: a laser log with known truth. Format `auto`: a CSV when `output` ends in
// .csv, a raw stream directory (odometry.csv, sensor_poses.csv) when its last component has no
// extension, else tuples. The logging fields (core/timing/logging_model.h) need a stream output.
struct SimulateOptions {
  std::string output;
  std::string truth;            // Where to write the truth as JSON; empty: not written.
  std::string format = "auto";  // auto, tuples, csv or stream.
  int intervals = 2000;
  double mean_interval = 0.8;     // Mean scan interval (s), without a free-running sensor.
  double interval_jitter = 0.02;  // Uniform ± jitter on each scan interval (s).
  std::uint64_t seed = 1;
  std::string trajectory = "rich";   // rich, straight, rotation or arc.
  double noise_xy = 0.001;           // Scan-matching noise σ on x and y (m).
  double noise_theta = 0.002;        // ... and on θ (rad).
  double outliers = 0.0;             // Fraction of slip outliers.
  double speed_time_constant = 0.5;  // s; 0: speeds constant within each interval.
  double segment_mean = 6.0;         // Mean time between new speed targets (s).
  double max_wheel_speed = 0.5;      // rad/s.
  double time_offset = 0.0;          // Scans stamped t were taken at t + this (s).
  double lateral_slip = 0.0;         // Lateral velocity = this·v·ω (s).
  double longitudinal_slip = 0.0;    // Forward velocity = v − this·dv/dt (s).
  double radius_change_time = -1.0;  // Time of a wheel-radius change (s); < 0: none.
  double r_l_after = 0.0;            // Radii after the change (m).
  double r_r_after = 0.0;
  // The logging model (0: off), stream output only.
  double sensor_period = 0.0;   // A sensor free-running at this period (s).
  double sensor_phase = 0.0;    // Its first sample (s).
  double sensor_drift = 0.0;    // Its clock's relative rate error.
  double logger_period = 0.0;   // A logger picking up the latest sample at this period (s).
  double logger_jitter = 0.0;   // σ of the pick-up times (of the stamps, without a logger) (s).
  double pickup_latency = 0.0;  // Fixed delay before a sample can be picked up (s).
  double encoder_period = 0.0;  // Encoder polls at this period (s); 0: at the scans.
  double encoder_poll_jitter = 0.0;   // σ of the true poll times (s).
  double encoder_stamp_jitter = 0.0;  // σ of the encoder stamps about the true polls (s).
  double repeat_fraction = 0.0;       // Share of records written twice.
  // Raw range scans (beams > 0): a lidar robot's recording (core/scan/scan_simulator.h), written
  // as the bag generators' robot-messages JSON (OUT.json) or a directory with odometry.csv and
  // scans.csv.
  int beams = 0;
  double field_of_view_deg = 360.0;
  double range_noise = 0.01;      // σ of the ranges (m).
  double missing_returns = 0.02;  // Share of beams without a return.
  double sweep = 0.0;             // Duration of one sweep (s); 0: instantaneous.
  std::string world = "mixed";    // rooms, corridor, clutter or mixed.
  bool upside_down = false;       // The lidar mounted upside down (its own scans; tf says so).
  bool self_returns = false;      // Parts of the robot in the lidar's view (AddMastAndGuard).
  // The motion flags given on the command line (max_wheel_speed, mean_interval, interval_jitter,
  // segment_mean, speed_time_constant): the scan robot keeps its own defaults for the others.
  std::set<std::string> given;
};
int RunSimulate(const SimulateOptions& options);

}  // namespace calib::cli

#endif  // CALIB_TOOLS_COMMANDS_COMMANDS_H_
