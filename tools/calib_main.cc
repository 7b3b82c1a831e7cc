// calib: offline calibration of a differential-drive robot from its own logs.
//   calib calibrate --input PATH --output OUT.json [--format ...] [--loss ...]
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gflags/gflags.h>

#include "core/laser_log_io.h"
#include "solvers/calibrate_laser.h"
#include "tools/laser_report.h"

DEFINE_string(input, "", "Laser log file (tuples or CSV), a raw-stream directory, or several "
                         "laser logs separated by commas to calibrate jointly");
DEFINE_string(output, "", "Where to write the JSON result");
DEFINE_string(format, "auto", "Laser log format: auto, tuples, csv or stream");
DEFINE_string(loss, "cauchy", "Robust loss: cauchy, huber or none");
DEFINE_double(loss_scale, 3.0, "Scale of the robust loss, in whitened residual units");
DEFINE_bool(quiet, false, "Do not print the summary on stdout");

namespace {

constexpr char kUsage[] =
    "calib <command> [flags]\n"
    "  calibrate --input PATH --output OUT.json   estimate the calibration\n"
    "  diagnose  --input PATH --output OUT.json   find physics the model leaves out\n";

int Fail(const std::string& message) {
  std::fprintf(stderr, "calib: error: %s\n", message.c_str());
  return 1;
}

std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream stream(text);
  std::string part;
  while (std::getline(stream, part, ',')) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

int Calibrate() {
  if (FLAGS_input.empty()) return Fail("--input is required");
  if (FLAGS_output.empty()) return Fail("--output is required");
  const calib::StatusOr<calib::LaserFormat> format = calib::ParseLaserFormat(FLAGS_format);
  if (!format.ok()) return Fail(format.message());
  const calib::StatusOr<calib::RobustLoss> loss = calib::ParseRobustLoss(FLAGS_loss);
  if (!loss.ok()) return Fail(loss.message());
  if (!(FLAGS_loss_scale > 0.0)) return Fail("--loss_scale must be positive");

  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  std::vector<calib::LaserLog> logs;
  for (const std::string& path : SplitCommas(FLAGS_input)) {
    calib::StatusOr<calib::LaserLog> log = calib::ReadLaserLog(path, *format);
    if (!log.ok()) return Fail(log.message());
    logs.push_back(std::move(log).value());
  }
  if (logs.empty()) return Fail("--input names no file");
  std::vector<const std::vector<calib::LaserInterval>*> intervals;
  for (const calib::LaserLog& log : logs) intervals.push_back(&log.intervals);

  calib::LaserCalibrationOptions options;
  options.refinement.loss = *loss;
  options.refinement.loss_scale = FLAGS_loss_scale;
  options.progress = [&](const std::string& line) {
    if (elapsed() > 1.0) std::fprintf(stderr, "calib: %.1f s: %s\n", elapsed(), line.c_str());
  };
  const calib::StatusOr<calib::LaserCalibrationResult> result =
      calib::CalibrateLaserJoint(intervals, options);
  if (!result.ok()) return Fail(FLAGS_input + ": " + result.message());

  nlohmann::ordered_json json = calib::LaserResultJson(*result, FLAGS_input, FLAGS_loss);
  json["seconds"]["total"] = elapsed();
  std::ofstream out(FLAGS_output);
  if (!out) return Fail("cannot write " + FLAGS_output);
  out << json.dump(2) << "\n";
  if (!out) return Fail("cannot write " + FLAGS_output);
  if (!FLAGS_quiet) {
    std::fputs(calib::LaserResultSummary(*result, FLAGS_input, FLAGS_loss).c_str(), stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  gflags::SetUsageMessage(kUsage);
  gflags::ParseCommandLineFlags(&argc, &argv, true);
  if (argc != 2) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const std::string command = argv[1];
  if (command == "calibrate") return Calibrate();
  if (command == "diagnose") return Fail("diagnose is not available in this build yet");
  std::fprintf(stderr, "calib: unknown command '%s'\n%s", command.c_str(), kUsage);
  return 2;
}
