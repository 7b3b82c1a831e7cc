// Calibrates a laser log in a few lines and, given OUT.json, writes the same report as
// `calib calibrate` through the report library: calib_consumer LOG [OUT.json]
#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/tools/report/json_output.h>
#include <calib/tools/report/laser_report.h>

#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2 && argc != 3) {
    std::fprintf(stderr, "usage: calib_consumer LOG [OUT.json]\n");
    return 2;
  }
  const calib::StatusOr<calib::LaserLog> log = calib::ReadLaserLog(argv[1]);
  if (!log.ok()) {
    std::fprintf(stderr, "%s\n", log.message().c_str());
    return 1;
  }
  const calib::StatusOr<calib::LaserCalibrationResult> result =
      calib::CalibrateLaser(log->intervals);
  if (!result.ok()) {
    std::fprintf(stderr, "%s\n", result.message().c_str());
    return 1;
  }
  const calib::LaserParamVector estimate = result->estimate.ToVector();
  for (int i = 0; i < calib::kNumLaserParams; ++i) {
    std::printf("%s = %.6g ± %.2g\n", calib::kLaserParamNames[i].c_str(), estimate(i),
                result->stddev(i));
  }
  if (argc == 3) {
    // The default loss of CalibrateLaser is Cauchy, as `calib calibrate`'s.
    const calib::Status written =
        calib::WriteJsonFile(argv[2], calib::LaserResultJson(*result, argv[1], "cauchy"));
    if (!written.ok()) {
      std::fprintf(stderr, "%s\n", written.message().c_str());
      return 1;
    }
  }
  return 0;
}
