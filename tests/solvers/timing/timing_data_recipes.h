#ifndef CALIB_TESTS_SOLVERS_TIMING_TIMING_DATA_RECIPES_H_
#define CALIB_TESTS_SOLVERS_TIMING_TIMING_DATA_RECIPES_H_

#include <calib/core/laser/laser_simulator.h>
#include <calib/core/timing/logging_model.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// The raw-stream logs of data/timing: how each is made from the laser simulator and its logging
// model (shared by the data tests and their generator; recipes in data/timing/README.md).
namespace calib::testing {

// data/timing in the source tree.
std::filesystem::path TimingDataDir();

struct TimingRecipe {
  std::string name;  // data/timing/<name>/ (odometry.csv, sensor_poses.csv, truth.json).
  LaserSimOptions sim;
  LoggingModel logging;
  bool biased = false;  // Claim: stamp-as-truth calibration ≥ 5 σ off in b or a radius.
  std::string cli;      // The `calib simulate` flags that make the same files.
};

std::vector<TimingRecipe> TimingRecipes();
void PrintTo(const TimingRecipe& recipe, std::ostream* os);

struct TimingGenerated {
  LaserStreams streams;
  LaserSimTruth truth;
  LoggedTimingTruth timing;
};
TimingGenerated Generate(const TimingRecipe& recipe);

// The streams with exact duplicate rows dropped (what the contract's stream reader does), as
// intervals: stamps taken as sample times.
StatusOr<LaserLog> StampAsTruthLog(const LaserStreams& streams, const std::string& source);

// Reads a stream directory's two CSV files as written, duplicates included.
StatusOr<LaserStreams> ReadStreamFiles(const std::filesystem::path& directory);

// (estimate − truth)/σ of `calib calibrate`'s calibration (default options) per parameter.
struct StampAsTruthFit {
  LaserCalibrationResult result;
  LaserParamVector error_sigmas;
};
StatusOr<StampAsTruthFit> FitStampAsTruth(const LaserStreams& streams, const LaserSimTruth& truth);

}  // namespace calib::testing

#endif  // CALIB_TESTS_SOLVERS_TIMING_TIMING_DATA_RECIPES_H_
