#ifndef CALIB_BENCHMARKS_BENCH_LASER_MC_REPORT_H_
#define CALIB_BENCHMARKS_BENCH_LASER_MC_REPORT_H_

#include <nlohmann/json.hpp>
#include <vector>

#include "benchmarks/bench_laser_monte_carlo.h"

// Tables and JSON of the laser Monte Carlo section.
namespace calib::bench {

// One scenario's table: √CRLB, RMSE, RMSE/√CRLB, bias, reported sigma and coverage per method.
void PrintMcScenario(const McScenarioResult& result);
nlohmann::json McScenarioJson(const McScenarioResult& result);

// The headline comparisons across scenarios (efficiency, outliers, where the closed form's
// assumptions break); returns them as JSON.
nlohmann::json PrintMcSummary(const std::vector<McScenarioResult>& results);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_LASER_MC_REPORT_H_
