#include <benchmark/benchmark.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/laser/censi_closed_form.h>

#include <memory>
#include <vector>

#include "benchmarks/bench_sections.h"

namespace calib::bench {
namespace {

// Console output as usual, plus every run kept for the JSON.
class CollectingReporter : public benchmark::ConsoleReporter {
 public:
  // Without colour: the table often goes to a file.
  CollectingReporter() : ConsoleReporter(OO_Tabular) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      results.push_back({{"name", run.benchmark_name()},
                         {"real_time", run.GetAdjustedRealTime()},
                         {"cpu_time", run.GetAdjustedCPUTime()},
                         {"time_unit", benchmark::GetTimeUnitString(run.time_unit)},
                         {"iterations", run.iterations}});
    }
  }
  nlohmann::json results = nlohmann::json::array();
};

LaserLog MicroLog(int intervals) {
  LaserSimOptions sim;
  sim.num_intervals = intervals;
  sim.speed_time_constant_s = 0.0;
  return SimulateLaserLog(sim);
}

}  // namespace

nlohmann::json RunMicroBenchmarks() {
  std::printf(
      "\nGoogle Benchmark micro-benchmarks (--benchmark_min_time=0.2; simulated log, "
      "seed 1, speed_time_constant_s=0):\n");
  std::fflush(stdout);
  const LaserLog log = MicroLog(1000);
  const LaserCalibration truth = [] {
    LaserCalibration c;
    const LaserSimOptions defaults;
    c.odometry = defaults.odometry;
    c.base_T_sensor = defaults.base_T_sensor;
    return c;
  }();
  const LaserParamVector p = truth.ToVector();
  const Eigen::Matrix3d sqrt_information = Eigen::Matrix3d::Identity();

  benchmark::RegisterBenchmark("LaserResidual/Evaluate+Jacobians", [&](benchmark::State& state) {
    const std::unique_ptr<ceres::CostFunction> cost(
        LaserResidual::Create(log.intervals[0], &sqrt_information));
    const double* parameters[2] = {p.data(), p.data() + 3};
    double residual[3], j_odometry[9], j_sensor[9];
    double* jacobians[2] = {j_odometry, j_sensor};
    for (auto _ : state) {
      benchmark::DoNotOptimize(cost->Evaluate(parameters, residual, jacobians));
      benchmark::ClobberMemory();
    }
  })->Unit(benchmark::kNanosecond);
  benchmark::RegisterBenchmark("LaserResidual/Evaluate", [&](benchmark::State& state) {
    const std::unique_ptr<ceres::CostFunction> cost(
        LaserResidual::Create(log.intervals[0], &sqrt_information));
    const double* parameters[2] = {p.data(), p.data() + 3};
    double residual[3];
    for (auto _ : state) {
      benchmark::DoNotOptimize(cost->Evaluate(parameters, residual, nullptr));
      benchmark::ClobberMemory();
    }
  })->Unit(benchmark::kNanosecond);
  benchmark::RegisterBenchmark("CensiClosedForm/1000", [&](benchmark::State& state) {
    for (auto _ : state) benchmark::DoNotOptimize(CensiClosedForm(log.intervals).ok());
  })->Unit(benchmark::kMicrosecond);

  // Google Benchmark reads its settings from argv; ours are not its business.
  std::vector<std::string> args = {"calib_bench", "--benchmark_min_time=0.2"};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  int argc = static_cast<int>(argv.size());
  benchmark::Initialize(&argc, argv.data());
  CollectingReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  std::printf(
      "(Google Benchmark prints its context on stderr; a \"Library was built as DEBUG\" warning "
      "there concerns the system's libbenchmark, not calib, which is built as Release.)\n");
  benchmark::ClearRegisteredBenchmarks();
  return {{"min_time_s", 0.2}, {"runs", reporter.results}};
}

}  // namespace calib::bench
