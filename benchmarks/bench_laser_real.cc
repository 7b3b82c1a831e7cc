#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "benchmarks/bench_sections.h"

namespace calib::bench {
namespace {

namespace fs = std::filesystem;

struct Published {
  LaserParamVector value;  // Radii (half the published diameters).
  LaserParamMatrix covariance;
};

StatusOr<Published> ReadPublished(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return Status::Io("cannot open " + path.string());
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded()) return Status::InvalidInput(path.string() + " is not valid JSON");
  Published p;
  p.value << j.at("l_diam").get<double>() / 2, j.at("r_diam").get<double>() / 2,
      j.at("axle").get<double>(), j.at("l_x").get<double>(), j.at("l_y").get<double>(),
      j.at("l_theta").get<double>();
  for (int r = 0; r < kNumLaserParams; ++r) {
    for (int c = 0; c < kNumLaserParams; ++c) p.covariance(r, c) = j.at("covariance")[r][c];
  }
  return p;
}

StatusOr<LaserCalibrationResult> CalibrateFile(const fs::path& path) {
  CALIB_ASSIGN_OR_RETURN(const LaserLog log, ReadLaserLog(path.string()));
  return CalibrateLaser(log.intervals);
}

// r and b are nearly proportional in the estimate (the data fix r/b well), so the regression
// slope cov(r_l, b)/var(r_l) is b/r when the covariance is over radii and b/d over diameters.
bool CovarianceIsOverRadii(const std::string& set, const Published& p, nlohmann::json* out) {
  const double slope = p.covariance(0, 2) / p.covariance(0, 0);
  const double corr = p.covariance(0, 2) / std::sqrt(p.covariance(0, 0) * p.covariance(2, 2));
  const double b_over_r = p.value(2) / p.value(0), b_over_d = p.value(2) / (2 * p.value(0));
  const bool radii = std::abs(std::log(slope / b_over_r)) < std::abs(std::log(slope / b_over_d));
  std::printf(
      "  %-9s cov(r_l,b)/var(r_l) = %.3f (correlation %.3f); b/r_l = %.3f, b/d_l = %.3f "
      "-> over %s\n",
      set.c_str(), slope, corr, b_over_r, b_over_d, radii ? "RADII" : "DIAMETERS");
  (*out)[set] = {{"slope", slope},
                 {"correlation", corr},
                 {"b_over_r", b_over_r},
                 {"b_over_d", b_over_d},
                 {"over_radii", radii}};
  return radii;
}

std::string Cell(int p, double v, const char* format = "%.3f") {
  return Format(format, ToDisplay(p, v, /*degrees=*/true));
}

// The three disjoint subsets X_0, X_1, X_2 of a set: the largest difference between two of
// them, absolute and in units of their combined sigma.
struct SubsetSpread {
  std::vector<LaserCalibrationResult> results;
  LaserParamVector spread = LaserParamVector::Zero();
  LaserParamVector spread_sigmas = LaserParamVector::Zero();
};

SubsetSpread CalibrateSubsets(const fs::path& dir, const std::string& set) {
  SubsetSpread out;
  for (int k = 0; k < 3; ++k) {
    const auto subset = CalibrateFile(dir / (set + "_" + std::to_string(k) + ".tuple"));
    if (!subset.ok()) {
      std::printf("%s_%d: FAILED: %s\n", set.c_str(), k, subset.message().c_str());
      continue;
    }
    out.results.push_back(*subset);
  }
  for (size_t a = 0; a < out.results.size(); ++a) {
    for (size_t b = a + 1; b < out.results.size(); ++b) {
      const LaserParamVector d = LaserError(out.results[a].estimate, out.results[b].estimate);
      const LaserParamVector s =
          (out.results[a].stddev.cwiseAbs2() + out.results[b].stddev.cwiseAbs2()).cwiseSqrt();
      out.spread = out.spread.cwiseMax(d.cwiseAbs());
      out.spread_sigmas = out.spread_sigmas.cwiseMax(d.cwiseAbs().cwiseQuotient(s));
    }
  }
  return out;
}

// One recording: ours (timed) against the published result, and the subsets' spread.
nlohmann::json RunSet(const fs::path& dir, const std::string& set, const Published& pub,
                      bool over_radii, int timing_runs) {
  std::vector<double> seconds;
  StatusOr<LaserCalibrationResult> ours = Status::Internal("not run");
  for (int run = 0; run < timing_runs; ++run) {
    const Stopwatch watch;
    ours = CalibrateFile(dir / (set + ".tuple"));
    seconds.push_back(watch.Seconds());
    if (!ours.ok()) break;
  }
  if (!ours.ok()) {
    std::printf("\n%s: FAILED: %s\n", set.c_str(), ours.message().c_str());
    return {{"error", ours.message()}};
  }
  const SubsetSpread subsets = CalibrateSubsets(dir, set);
  LaserParamVector pub_sigma_radius = pub.covariance.diagonal().cwiseSqrt();
  if (!over_radii) pub_sigma_radius.head<2>() /= 2;  // σ_r = σ_d / 2.
  const LaserParamVector value = ours->estimate.ToVector();
  LaserParamVector diff = value - pub.value;
  diff(5) = WrapAngle(diff(5));

  std::printf(
      "\n%s: %d intervals, %d inliers, scan noise (%.3g mm, %.3g mm, %.3g mrad), "
      "%d iterations; wall time %.3f s (median of %d; min %.3f, max %.3f)\n",
      set.c_str(), ours->samples, ours->inliers, ours->noise_sigma[0](0) * 1e3,
      ours->noise_sigma[0](1) * 1e3, ours->noise_sigma[0](2) * 1e3, ours->iterations,
      Median(seconds), timing_runs, *std::min_element(seconds.begin(), seconds.end()),
      *std::max_element(seconds.begin(), seconds.end()));
  TextTable table({"param", "ours", "published", "diff", "pub sigma", "diff/pub sigma", "our sigma",
                   "diff/our sigma", "subset spread", "spread/sigma"});
  for (int p = 0; p < kNumLaserParams; ++p) {
    table.AddRow({kLaserParamNames[p], Cell(p, value(p), "%.4f"), Cell(p, pub.value(p), "%.4f"),
                  Cell(p, diff(p), "%+.4f"), Cell(p, pub_sigma_radius(p), "%.4f"),
                  Format("%+.2f", diff(p) / pub_sigma_radius(p)), Cell(p, ours->stddev(p), "%.4f"),
                  Format("%+.2f", diff(p) / ours->stddev(p)), Cell(p, subsets.spread(p), "%.4f"),
                  Format("%.2f", subsets.spread_sigmas(p))});
  }
  table.Print();
  nlohmann::json subsets_json;
  for (const auto& s : subsets.results) {
    subsets_json.push_back({{"estimate", ToJson(s.estimate.ToVector())},
                            {"stddev", ToJson(s.stddev)},
                            {"inliers", s.inliers},
                            {"samples", s.samples}});
  }
  return {{"intervals", ours->samples},
          {"inliers", ours->inliers},
          {"iterations", ours->iterations},
          {"noise_sigma", ToJson(ours->noise_sigma[0])},
          {"estimate", ToJson(value)},
          {"stddev", ToJson(ours->stddev)},
          {"closed_form", ToJson(ours->closed_form.calibration.ToVector())},
          {"published", ToJson(pub.value)},
          {"published_sigma", ToJson(pub_sigma_radius)},
          {"difference", ToJson(diff)},
          {"difference_over_published_sigma",
           ToJson(LaserParamVector(diff.cwiseQuotient(pub_sigma_radius)))},
          {"difference_over_our_sigma", ToJson(LaserParamVector(diff.cwiseQuotient(ours->stddev)))},
          {"subsets", subsets_json},
          {"subset_max_difference", ToJson(subsets.spread)},
          {"subset_max_difference_over_sigma", ToJson(subsets.spread_sigmas)},
          {"seconds", seconds},
          {"median_seconds", Median(seconds)}};
}

}  // namespace

nlohmann::json RunLaserReal(const BenchConfig& config) {
  std::printf("\n=== Section laser_real: the Censi et al. recordings ===\n");
  const fs::path dir = config.censi_dir;
  nlohmann::json out;
  if (!fs::exists(dir / "l90.tuple")) {
    std::printf("SKIPPED: the recordings are not at %s (pass --censi_dir)\n", dir.c_str());
    out["skipped"] = "no data at " + dir.string();
    return out;
  }
  const int timing_runs = 5;
  std::printf(
      "Data: %s. Ours: CalibrateLaser defaults (Cauchy, noise estimated). Published: the "
      "authors' closed form + trimming.\nUnits: mm, deg. Wall time: ReadLaserLog + "
      "CalibrateLaser, median of %d runs. Subset spread: max over pairs of X_0, X_1, X_2 "
      "of |difference| and of |difference| / sqrt(sigma_a^2 + sigma_b^2).\n",
      dir.c_str(), timing_runs);
  std::printf("Units of the published covariance:\n");
  out["data_dir"] = dir.string();
  out["timing_runs"] = timing_runs;
  const std::vector<std::string> sets = {"l90", "lmov", "lstraight"};
  std::vector<Published> published;
  for (const std::string& set : sets) {
    const StatusOr<Published> p = ReadPublished(dir / (set + "_results.json"));
    if (!p.ok()) {
      std::printf("SKIPPED: %s\n", p.message().c_str());
      out["skipped"] = p.message();
      return out;
    }
    published.push_back(*p);
  }
  int radii_votes = 0;
  for (size_t i = 0; i < sets.size(); ++i) {
    radii_votes += CovarianceIsOverRadii(sets[i], published[i], &out["covariance_units_check"]);
  }
  const bool over_radii = radii_votes * 2 > static_cast<int>(sets.size());
  out["published_covariance_over"] = over_radii ? "radii" : "diameters";
  std::printf("  => published sigmas taken as over %s\n", over_radii ? "radii" : "diameters");

  for (size_t i = 0; i < sets.size(); ++i) {
    out["sets"][sets[i]] = RunSet(dir, sets[i], published[i], over_radii, timing_runs);
  }
  return out;
}

}  // namespace calib::bench
