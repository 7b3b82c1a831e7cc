// `calib simulate --beams N`: a lidar robot's raw scans and wheel angles with the truth.
#include <calib/core/bag/robot_messages_json.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/scan/csm_log.h>
#include <calib/core/scan/scan_csv.h>
#include <calib/core/scan/scan_simulator.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/simulate_scans.h>
#include <calib/tools/report/json_output.h>
#include <calib/tools/report/laser_report.h>

#include <filesystem>

namespace calib::cli {
namespace {

StatusOr<WorldKind> ParseWorld(const std::string& name) {
  return ParseChoice<WorldKind>("world", name,
                                {{"rooms", WorldKind::kRooms},
                                 {"corridor", WorldKind::kCorridor},
                                 {"clutter", WorldKind::kClutter},
                                 {"mixed", WorldKind::kMixed}},
                                "rooms, corridor, clutter, mixed");
}

StatusOr<ScanSimOptions> ScanOptions(const SimulateOptions& flags, const LaserSimOptions& laser,
                                     const LoggingModel& model) {
  ScanSimOptions o;
  o.laser = DefaultScanLaserOptions();
  o.laser.num_intervals = laser.num_intervals;
  o.laser.seed = laser.seed;
  o.laser.trajectory = laser.trajectory;
  o.laser.effects = laser.effects;
  // The motion flags given replace the scan robot's own defaults.
  const auto given = [&](const char* name) { return flags.given.count(name) > 0; };
  if (given("max_wheel_speed")) o.laser.max_wheel_speed = laser.max_wheel_speed;
  if (given("mean_interval")) o.laser.mean_interval_s = laser.mean_interval_s;
  if (given("interval_jitter")) o.laser.interval_jitter_s = laser.interval_jitter_s;
  if (given("segment_mean")) o.laser.segment_mean_s = laser.segment_mean_s;
  if (given("speed_time_constant")) o.laser.speed_time_constant_s = laser.speed_time_constant_s;
  if (!model.IsClean()) o.logging = model;
  CALIB_ASSIGN_OR_RETURN(o.world.kind, ParseWorld(flags.world));
  o.world.seed = flags.seed;
  o.beams = flags.beams;
  o.field_of_view_rad = flags.field_of_view_deg * M_PI / 180.0;
  o.range_noise_sigma_m = flags.range_noise;
  o.missing_probability = flags.missing_returns;
  o.sweep_s = flags.sweep;
  o.upside_down = flags.upside_down;
  if (flags.self_returns) AddMastAndGuard(&o);
  o.seed = flags.seed;
  return o;
}

nlohmann::ordered_json ScanTruthJson(const ScanSimulation& sim, const SimulateOptions& flags) {
  LaserSimTruth truth;
  truth.odometry = sim.truth.odometry;
  truth.base_T_sensor = sim.truth.base_T_sensor;
  truth.effects = sim.truth.effects;
  nlohmann::ordered_json json = LaserSimTruthJson(truth);
  json["simulation"] = {{"scans", sim.scans.size()},
                        {"beams", flags.beams},
                        {"field_of_view_deg", flags.field_of_view_deg},
                        {"range_noise", flags.range_noise},
                        {"missing_returns", flags.missing_returns},
                        {"sweep", flags.sweep},
                        {"world", flags.world},
                        {"upside_down", flags.upside_down},
                        {"self_returns", flags.self_returns},
                        {"seed", flags.seed},
                        {"trajectory", flags.trajectory}};
  return json;
}

}  // namespace

int SimulateScanRobot(const SimulateOptions& flags, const LaserSimOptions& laser,
                      const LoggingModel& model) {
  const StatusOr<ScanSimOptions> options = ScanOptions(flags, laser, model);
  if (!options.ok()) return Fail(options.message());
  const StatusOr<ScanSimulation> sim = SimulateScans(*options);
  if (!sim.ok()) return Fail(sim.message());
  const std::filesystem::path path(flags.output);
  Status written;
  if (flags.upside_down && path.extension() != ".json") {
    return Fail(
        "--upside_down needs OUT.json: a scans directory or CSM log has no tf to say the lidar "
        "is upside down, and its scans would be taken as an upright lidar's");
  }
  if (path.extension() == ".json") {
    written = WriteRobotMessagesJson(ScanSimulationMessages(*sim), flags.output);
  } else if (path.extension() == ".log") {
    // As Censi et al.'s Khepera logged it: counts of its encoders, stamps of 2008.
    written = WriteWholeFile(
        flags.output, CsmLogText(sim->scans, sim->encoders, kCensiKheperaCountsPerTurn, 1.2e9));
  } else if (!path.has_extension()) {
    written = WriteLaserStream(sim->encoders, {}, flags.output);
    if (written.ok()) {
      std::filesystem::remove(path / "sensor_poses.csv");
      written = WriteScanCsv(sim->scans, ScanCsvLayout::kWide, (path / "scans.csv").string());
    }
  } else {
    return Fail(
        "--beams writes OUT.json (robot messages for the bag generators), OUT.log (a CSM laser "
        "log with wheel encoder counts, as Censi et al.'s) or a directory (odometry.csv, "
        "scans.csv), got " +
        flags.output);
  }
  if (!written.ok()) return Fail(written.message());
  if (flags.truth.empty()) return 0;
  const Status truth = WriteJsonFile(flags.truth, ScanTruthJson(*sim, flags));
  return truth.ok() ? 0 : Fail(truth.message());
}

}  // namespace calib::cli
