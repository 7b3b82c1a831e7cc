#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  const calib::StatusOr<calib::LaserLog> log = calib::ReadLaserLog(argv[1]);
  if (!log.ok()) {  // log.code(): kIo, kInvalidInput, ...
    std::fprintf(stderr, "%s\n", log.message().c_str());
    return 1;
  }
  const calib::StatusOr<calib::LaserCalibrationResult> result =
      calib::CalibrateLaser(log->intervals);
  if (!result.ok()) {  // e.g. kNotObservable: which motion is missing
    std::fprintf(stderr, "%s\n", result.message().c_str());
    return 1;
  }
  const calib::LaserParamVector estimate = result->estimate.ToVector();
  for (int i = 0; i < calib::kNumLaserParams; ++i) {
    std::printf("%s = %.6g ± %.2g\n", calib::kLaserParamNames[i].c_str(), estimate(i),
                result->stddev(i));
  }
  // Also result->covariance, inliers, converged, warnings, observability.warnings.
  return 0;
}
