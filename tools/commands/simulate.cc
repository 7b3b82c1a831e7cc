// `calib simulate`: writes a simulated laser log and, with --truth, the truth it was made from.
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/commands.h>
#include <calib/tools/report/json_output.h>
#include <calib/tools/report/laser_report.h>

namespace calib::cli {
namespace {

StatusOr<LaserTrajectory> ParseTrajectory(const std::string& name) {
  return ParseChoice<LaserTrajectory>("trajectory", name,
                                      {{"rich", LaserTrajectory::kRich},
                                       {"straight", LaserTrajectory::kStraight},
                                       {"rotation", LaserTrajectory::kPureRotation},
                                       {"arc", LaserTrajectory::kConstantArc}},
                                      "rich, straight, rotation, arc");
}

StatusOr<LaserSimOptions> SimulatorOptions(const SimulateOptions& flags) {
  LaserSimOptions options;
  options.num_intervals = flags.intervals;
  options.seed = flags.seed;
  CALIB_ASSIGN_OR_RETURN(options.trajectory, ParseTrajectory(flags.trajectory));
  if (flags.intervals <= 0) return Status::InvalidInput("--intervals must be positive");
  options.scan_noise_sigma = Eigen::Vector3d(flags.noise_xy, flags.noise_xy, flags.noise_theta);
  options.outlier_fraction = flags.outliers;
  options.speed_time_constant_s = flags.speed_time_constant;
  options.segment_mean_s = flags.segment_mean;
  options.max_wheel_speed = flags.max_wheel_speed;
  if (flags.speed_time_constant < 0.0 || !(flags.segment_mean > 0.0) ||
      !(flags.max_wheel_speed > 0.0)) {
    return Status::InvalidInput(
        "--speed_time_constant must be >= 0, --segment_mean and --max_wheel_speed > 0");
  }
  options.effects.time_offset_s = flags.time_offset;
  options.effects.lateral_slip_s = flags.lateral_slip;
  options.effects.longitudinal_slip_s = flags.longitudinal_slip;
  options.effects.radius_change_time_s = flags.radius_change_time;
  options.effects.left_radius_after_m = flags.r_l_after;
  options.effects.right_radius_after_m = flags.r_r_after;
  return options;
}

// The truth, and the settings that made it.
nlohmann::ordered_json TruthJson(const LaserSimTruth& truth, const SimulateOptions& flags) {
  nlohmann::ordered_json json = LaserSimTruthJson(truth);
  json["simulation"] = {{"intervals", flags.intervals},
                        {"seed", flags.seed},
                        {"trajectory", flags.trajectory},
                        {"noise_xy", flags.noise_xy},
                        {"noise_theta", flags.noise_theta},
                        {"outliers", flags.outliers},
                        {"speed_time_constant", flags.speed_time_constant},
                        {"segment_mean", flags.segment_mean},
                        {"max_wheel_speed", flags.max_wheel_speed}};
  return json;
}

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() > suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

int RunSimulate(const SimulateOptions& flags) {
  if (flags.output.empty()) return Fail("--output is required");
  const StatusOr<LaserSimOptions> options = SimulatorOptions(flags);
  if (!options.ok()) return Fail(options.message());
  LaserSimTruth truth;
  const LaserLog log = SimulateLaserLog(*options, &truth);
  const Status written = EndsWith(flags.output, ".csv") ? WriteLaserCsv(log, flags.output)
                                                        : WriteLaserTuples(log, flags.output);
  if (!written.ok()) return Fail(written.message());
  if (flags.truth.empty()) return 0;
  const Status truth_written = WriteJsonFile(flags.truth, TruthJson(truth, flags));
  return truth_written.ok() ? 0 : Fail(truth_written.message());
}

}  // namespace calib::cli
