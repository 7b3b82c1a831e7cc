// calib_bench: accuracy (Monte Carlo against the Cramér–Rao bound), the published real data, and
// speed/memory of the laser–odometry calibration. Every number is measured by this run.
#include <calib/tools/process_memory.h>
#include <calib/tools/report/json_output.h>
#include <gflags/gflags.h>

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <set>
#include <sstream>

#include "benchmarks/bench_common.h"
#include "benchmarks/bench_diagnose.h"
#include "benchmarks/bench_laser_monte_carlo.h"
#include "benchmarks/bench_plot.h"
#include "benchmarks/bench_process.h"
#include "benchmarks/bench_sections.h"
#include "benchmarks/bench_timing_study.h"

DEFINE_bool(quick, false, "Reduced grid and seeds (CI smoke test, under a minute)");
DEFINE_string(json, "", "Write every result to this JSON file (and the RMSE plot beside it)");
DEFINE_string(sections, "laser_mc,laser_real,bearing,diagnose,timing,scans,robust_scale,speed",
              "Comma-separated sections to run");
DEFINE_int32(
    seeds, 0,
    "Seeds (logs) per Monte Carlo scenario (0: each section's default, fewer with --quick)");
DEFINE_string(censi_dir, CALIB_CENSI_DATA_DIR, "Folder with the Censi et al. recordings");
DEFINE_int32(threads, 2, "Monte Carlo seeds run in parallel on this many threads");
DEFINE_string(peer_solver, "",
              "speed: a peer solver binary run end to end beside `calib calibrate` (e.g. the "
              "authors' solver2)");
DEFINE_string(peer_args, "-input_file {input} -output_file {output} -mode 0 -outliers_iterations 4",
              "speed: the peer's arguments; {input} is the log, {output} a file in its own "
              "folder (default: the authors' solver2 as in their run_all.sh)");
DEFINE_string(calib_cli, "", "speed: the calib binary (default: `calib` next to calib_bench)");
DEFINE_string(calib_args, "calibrate --input {input} --output {output} --quiet",
              "speed: calib's arguments, placeholders as in --peer_args");
DEFINE_int32(speed_reps, 0, "speed: interleaved end-to-end rounds (0: 7, 3 with --quick)");
// Internal: the speed section re-executes this binary once per N to measure its memory peak.
DEFINE_int64(speed_child, 0, "(internal) parse and calibrate --speed_file of this many intervals");
DEFINE_string(speed_file, "", "(internal) the log for --speed_child");

namespace calib::bench {
namespace {

constexpr const char* kUsage =
    "calib_bench [--quick] [--json OUT.json] [--sections "
    "laser_mc,laser_real,bearing,diagnose,timing,scans,robust_scale,speed] [--seeds N] "
    "[--censi_dir DIR] [--peer_solver PATH [--peer_args ARGS]] [--calib_cli PATH] [--speed_reps R]";

std::set<std::string> ParseSections(const std::string& text, bool* ok) {
  const std::set<std::string> known = {"laser_mc", "laser_real", "bearing",      "diagnose",
                                       "timing",   "scans",      "robust_scale", "speed"};
  std::set<std::string> sections;
  std::stringstream stream(text);
  std::string name;
  *ok = true;
  while (std::getline(stream, name, ',')) {
    if (name.empty()) continue;
    if (known.count(name) == 0) {
      std::fprintf(
          stderr,
          "unknown section '%s' (expected laser_mc, laser_real, bearing, diagnose, timing, scans, "
          "robust_scale, speed)\n",
          name.c_str());
      *ok = false;
    }
    sections.insert(name);
  }
  return sections;
}

// RMSE against N for b and sensor_x, default noise without outliers, with the √CRLB line; false
// when the file could not be written.
bool WritePlot(const std::vector<McScenarioResult>& results, const std::string& path) {
  const char* colors[kNumMcMethods] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728"};
  std::vector<PlotPanel> panels;
  for (int param : {2, 3}) {
    PlotPanel panel;
    panel.title = "RMSE of " + kLaserParamNames[param] + " (mm)";
    panel.x_label = "N (intervals)";
    panel.y_label = kLaserParamNames[param] + " RMSE, mm";
    PlotSeries crlb{"sqrt(CRLB)", {}, {}, "#000000", true};
    std::vector<PlotSeries> methods(kNumMcMethods);
    const char* markers[kNumMcMethods] = {"ring", "square", "circle", "circle"};
    for (int m = 0; m < kNumMcMethods; ++m) {
      methods[m] = {kMcMethodNames[m], {}, {}, colors[m], false, markers[m]};
    }
    for (const McScenarioResult& r : results) {
      const McScenario& s = r.scenario;
      if (s.kind != "gaussian" || s.outlier_fraction > 0 ||
          std::abs(s.scan_sigma(0) - 0.001) > 1e-9)
        continue;
      crlb.x.push_back(s.intervals);
      crlb.y.push_back(r.crlb_sd(param) * 1e3);
      for (int m = 0; m < kNumMcMethods; ++m) {
        methods[m].x.push_back(s.intervals);
        methods[m].y.push_back(r.methods[m].rmse(param) * 1e3);
      }
    }
    panel.series = methods;
    panel.series.push_back(crlb);
    panels.push_back(panel);
  }
  const int seeds = results.empty() ? 0 : results.front().scenario.seeds;
  const Status written = WriteLogLogSvg(
      path,
      Format("Monte Carlo RMSE vs N: scan noise (1 mm, 1 mm, 2 mrad), no outliers, %d seeds",
             seeds),
      panels);
  std::printf("%s %s\n", written.ok() ? "Plot written to" : "Plot FAILED:",
              written.ok() ? path.c_str() : written.message().c_str());
  return written.ok();
}

int Main(int argc, char** argv) {
  // Internal, before the flags: the speed section's launcher passes the command through as is.
  if (argc > 1 && std::string(argv[1]) == "--measure_child") return RunLauncherMain(argc, argv);
  gflags::SetUsageMessage(kUsage);
  gflags::ParseCommandLineFlags(&argc, &argv, true);
  if (FLAGS_speed_child > 0) return RunSpeedChild(FLAGS_speed_file, FLAGS_speed_child);
  bool ok = true;
  const std::set<std::string> sections = ParseSections(FLAGS_sections, &ok);
  if (!ok) return 2;

  BenchConfig config;
  config.quick = FLAGS_quick;
  config.seeds = FLAGS_seeds;
  config.threads = std::max(1, FLAGS_threads);
  // Absolute: the speed section's child processes run in folders of their own.
  std::error_code absolute_error;
  config.censi_dir = std::filesystem::absolute(FLAGS_censi_dir, absolute_error).string();
  if (absolute_error || FLAGS_censi_dir.empty()) config.censi_dir = FLAGS_censi_dir;
  config.calib_cli = FLAGS_calib_cli;
  config.calib_args = FLAGS_calib_args;
  config.peer_solver = FLAGS_peer_solver;
  config.peer_args = FLAGS_peer_args;
  config.speed_reps = FLAGS_speed_reps;
  std::error_code error;
  config.self_path = std::filesystem::read_symlink("/proc/self/exe", error).string();
  if (error) config.self_path = argv[0];

  const std::time_t now = std::time(nullptr);
  char stamp[64];
  std::strftime(stamp, sizeof(stamp), "%Y-%m-%d %H:%M:%S", std::localtime(&now));
  std::printf("calib_bench (%s mode) started %s; sections %s; threads %d\n",
              config.quick ? "quick" : "full", stamp, FLAGS_sections.c_str(), config.threads);
  nlohmann::json root = {{"mode", config.quick ? "quick" : "full"},
                         {"started", stamp},
                         {"sections", std::vector<std::string>(sections.begin(), sections.end())},
                         {"threads", config.threads},
                         {"censi_dir", config.censi_dir}};
  const Stopwatch total;
  std::vector<McScenarioResult> mc_results;
  if (sections.count("laser_mc")) root["laser_mc"] = RunLaserMonteCarlo(config, &mc_results);
  std::fflush(stdout);
  if (sections.count("laser_real")) root["laser_real"] = RunLaserReal(config);
  std::fflush(stdout);
  if (sections.count("bearing")) root["bearing"] = RunBearingBench(config);
  std::fflush(stdout);
  if (sections.count("diagnose")) root["diagnose"] = RunDiagnoseBench(config.quick, FLAGS_seeds);
  std::fflush(stdout);
  if (sections.count("timing")) root["timing"] = RunTimingStudy(config);
  std::fflush(stdout);
  if (sections.count("scans")) root["scans"] = RunScansBench(config);
  std::fflush(stdout);
  if (sections.count("robust_scale")) root["robust_scale"] = RunRobustScale(config);
  std::fflush(stdout);
  if (sections.count("speed")) root["speed"] = RunSpeed(config);
  root["seconds"] = total.Seconds();

  if (!FLAGS_json.empty()) {
    if (WriteJsonFile(FLAGS_json, root, 1).ok()) {
      std::printf("\nResults written to %s\n", FLAGS_json.c_str());
    } else {
      std::printf("\nFAILED to write %s\n", FLAGS_json.c_str());
      std::fprintf(stderr, "calib_bench: error: cannot write %s\n", FLAGS_json.c_str());
      ok = false;
    }
    if (!mc_results.empty()) {
      std::filesystem::path plot = FLAGS_json;
      plot.replace_extension();
      ok = WritePlot(mc_results, plot.string() + "_rmse.svg") && ok;
    }
  } else if (!mc_results.empty()) {
    std::printf("\n(no --json: the RMSE plot is not written)\n");
  }
  std::printf("calib_bench finished in %.1f s\n", total.Seconds());
  // The tables on stdout count as output too: a full disk behind them is a failure.
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    std::fprintf(stderr, "calib_bench: error: cannot write to standard output\n");
    ok = false;
  }
  return ok ? 0 : 1;
}

}  // namespace
}  // namespace calib::bench

int main(int argc, char** argv) {
  calib::KeepFreedMemory();  // As `calib` does: the speed section measures what users get.
  return calib::bench::Main(argc, argv);
}
