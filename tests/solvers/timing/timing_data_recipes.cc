#include "tests/solvers/timing/timing_data_recipes.h"

#include <calib/core/csv.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/text_file.h>

#include <ostream>
#include <utility>

namespace calib::testing {

std::filesystem::path TimingDataDir() {
  return std::filesystem::path(CALIB_SOURCE_DIR) / "data" / "timing";
}

namespace {

// The robot of the issue: a scanner free-running at 99.5 ms (clock 2e-4 fast) stamped at a
// 100 ms logger's pick-up, encoder polls every 257 ms stamped with 17 ms of scatter, a few
// records written twice.
LoggingModel RobotLikeLogging() {
  LoggingModel m;
  m.sensor_period_s = 0.0995;
  m.sensor_phase_s = 0.013;
  m.sensor_clock_drift = 2e-4;
  m.logger_period_s = 0.1;
  m.logger_jitter_s = 0.005;
  m.encoder_period_s = 0.257;
  m.encoder_poll_jitter_s = 0.003;
  m.encoder_stamp_jitter_s = 0.017;
  m.repeat_fraction = 0.01;
  return m;
}

// The same sensor and encoder rates, every stamp the true sample time.
LoggingModel CleanLogging() {
  LoggingModel m;
  m.sensor_period_s = 0.0995;
  m.sensor_phase_s = 0.013;
  m.encoder_period_s = 0.257;
  return m;
}

LaserSimOptions RobotLikeMotion(uint64_t seed) {
  LaserSimOptions sim;
  sim.num_intervals = 3000;
  sim.max_wheel_speed = 8.0;
  sim.scan_noise_sigma = Eigen::Vector3d(0.0005, 0.0005, 0.001);
  sim.seed = seed;
  return sim;
}

TimingRecipe Make(const std::string& name, const LaserSimOptions& sim, const LoggingModel& logging,
                  bool biased, const std::string& cli) {
  TimingRecipe recipe;
  recipe.name = name;
  recipe.sim = sim;
  recipe.logging = logging;
  recipe.biased = biased;
  recipe.cli = cli;
  return recipe;
}

}  // namespace

std::vector<TimingRecipe> TimingRecipes() {
  const std::string motion =
      "--intervals 3000 --max_wheel_speed 8 --noise_xy 0.0005 --noise_theta 0.001";
  const std::string clean = " --sensor_period 0.0995 --sensor_phase 0.013 --encoder_period 0.257";
  const std::string robot = clean +
                            " --sensor_drift 2e-4 --logger_period 0.1 --logger_jitter 0.005"
                            " --encoder_poll_jitter 0.003 --encoder_stamp_jitter 0.017"
                            " --repeat_fraction 0.01";
  return {
      Make("robot_like", RobotLikeMotion(4), RobotLikeLogging(), true,
           motion + " --seed 4" + robot),
      Make("clean", RobotLikeMotion(4), CleanLogging(), false, motion + " --seed 4" + clean),
  };
}

void PrintTo(const TimingRecipe& recipe, std::ostream* os) { *os << recipe.name; }

TimingGenerated Generate(const TimingRecipe& recipe) {
  TimingGenerated g;
  g.streams = SimulateLoggedLaserStreams(recipe.sim, recipe.logging, &g.truth, &g.timing);
  return g;
}

StatusOr<LaserLog> StampAsTruthLog(const LaserStreams& streams, const std::string& source) {
  LaserStreams kept;
  for (const EncoderSample& s : streams.odometry) {
    const bool duplicate = !kept.odometry.empty() && kept.odometry.back().t_s == s.t_s &&
                           kept.odometry.back().left_rad == s.left_rad &&
                           kept.odometry.back().right_rad == s.right_rad;
    if (!duplicate) kept.odometry.push_back(s);
  }
  for (const StampedPose& p : streams.sensor_poses) {
    const bool duplicate = !kept.sensor_poses.empty() && kept.sensor_poses.back().t_s == p.t_s &&
                           kept.sensor_poses.back().world_T_sensor == p.world_T_sensor;
    if (!duplicate) kept.sensor_poses.push_back(p);
  }
  return LaserLogFromStreams(kept.odometry, kept.sensor_poses, source);
}

StatusOr<LaserStreams> ReadStreamFiles(const std::filesystem::path& directory) {
  LaserStreams streams;
  std::string text;
  const std::string odometry = (directory / "odometry.csv").string();
  CALIB_RETURN_IF_ERROR(ReadWholeFile(odometry, &text));
  {
    CALIB_ASSIGN_OR_RETURN(CsvReader csv,
                           CsvReader::Open(text, odometry, {{"t"}, {"left"}, {"right"}}));
    while (true) {
      CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
      if (!more) break;
      EncoderSample s;
      CALIB_RETURN_IF_ERROR(csv.Number(0, &s.t_s));
      CALIB_RETURN_IF_ERROR(csv.Number(1, &s.left_rad));
      CALIB_RETURN_IF_ERROR(csv.Number(2, &s.right_rad));
      streams.odometry.push_back(s);
    }
  }
  const std::string poses = (directory / "sensor_poses.csv").string();
  CALIB_RETURN_IF_ERROR(ReadWholeFile(poses, &text));
  CALIB_ASSIGN_OR_RETURN(CsvReader csv,
                         CsvReader::Open(text, poses, {{"t"}, {"x"}, {"y"}, {"theta"}}));
  while (true) {
    CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
    if (!more) break;
    StampedPose p;
    CALIB_RETURN_IF_ERROR(csv.Number(0, &p.t_s));
    for (int j = 0; j < 3; ++j) CALIB_RETURN_IF_ERROR(csv.Number(j + 1, &p.world_T_sensor(j)));
    streams.sensor_poses.push_back(p);
  }
  return streams;
}

StatusOr<StampAsTruthFit> FitStampAsTruth(const LaserStreams& streams, const LaserSimTruth& truth) {
  CALIB_ASSIGN_OR_RETURN(const LaserLog log, StampAsTruthLog(streams, "streams"));
  StampAsTruthFit fit;
  LaserCalibrationOptions options;
  options.interval_jitter = false;  // Stamps taken as the sample times, nothing more.
  CALIB_ASSIGN_OR_RETURN(fit.result, CalibrateLaser(log.intervals, options));
  const LaserCalibration exact{truth.odometry, truth.base_T_sensor};
  fit.error_sigmas =
      (fit.result.estimate.ToVector() - exact.ToVector()).cwiseQuotient(fit.result.stddev);
  return fit;
}

}  // namespace calib::testing
