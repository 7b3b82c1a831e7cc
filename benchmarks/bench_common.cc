#include "benchmarks/bench_common.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

namespace calib::bench {

void ParallelFor(int n, int threads, const std::function<void(int)>& f) {
  std::atomic<int> next{0};
  const auto worker = [&]() {
    for (int i = next++; i < n; i = next++) f(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min(threads, n); ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& thread : pool) thread.join();
}

double Median(std::vector<double> values) {
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end());
  const size_t mid = values.size() / 2;
  return values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
}

double LogLogSlope(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

double ToDisplay(int param, double value, bool degrees) {
  if (param < 5) return value * 1e3;
  return degrees ? value * 180.0 / M_PI : value * 1e3;
}

LaserParamVector LaserError(const LaserCalibration& estimate, const LaserCalibration& truth) {
  LaserParamVector d = estimate.ToVector() - truth.ToVector();
  d(5) = WrapAngle(d(5));
  return d;
}

nlohmann::json ToJson(const LaserParamVector& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

nlohmann::json ToJson(const Eigen::Vector3d& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

void TextTable::Print(std::FILE* out) const {
  std::vector<size_t> width(header_.size(), 0);
  const auto measure = [&](const std::vector<std::string>& row) {
    if (row.size() == 1 && row[0] == "-") return;
    for (size_t c = 0; c < row.size() && c < width.size(); ++c) {
      width[c] = std::max(width[c], row[c].size());
    }
  };
  measure(header_);
  for (const auto& row : rows_) measure(row);
  size_t total = 0;
  for (size_t w : width) total += w + 2;
  const auto print_row = [&](const std::vector<std::string>& row) {
    if (row.size() == 1 && row[0] == "-") {
      std::fprintf(out, "  %s\n", std::string(total - 2, '-').c_str());
      return;
    }
    std::fprintf(out, " ");
    for (size_t c = 0; c < width.size(); ++c) {
      const std::string cell = c < row.size() ? row[c] : "";
      const int w = static_cast<int>(width[c]);
      std::fprintf(out, c == 0 ? " %-*s" : "  %*s", w, cell.c_str());
    }
    std::fprintf(out, "\n");
  };
  print_row(header_);
  print_row({"-"});
  for (const auto& row : rows_) print_row(row);
}

}  // namespace calib::bench
