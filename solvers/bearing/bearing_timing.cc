#include <calib/solvers/bearing/bearing_text.h>
#include <calib/solvers/bearing/bearing_timing.h>
#include <calib/solvers/stats/score_test.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace calib {
namespace {

// Maximum of a unimodal f on [a, b] by golden section; returns the argument.
double GoldenMax(const std::function<double(double)>& f, double a, double b, int iterations = 60) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = f(c), fd = f(d);
  for (int i = 0; i < iterations; ++i) {
    if (fc >= fd) {
      b = d, d = c, fd = fc;
      c = b - g * (b - a);
      fc = f(c);
    } else {
      a = c, c = d, fc = fd;
      d = a + g * (b - a);
      fd = f(d);
    }
  }
  return fc >= fd ? c : d;
}

struct Profile {
  const std::vector<double>& e2;  // ẽ².
  const std::vector<double>& g2;  // Rates².
  double mean_e2 = 0.0;
  double LogLikelihood(double sigma2, double jitter2) const {
    double sum = 0.0;
    for (size_t k = 0; k < e2.size(); ++k) {
      const double v = sigma2 + jitter2 * g2[k];
      sum += std::log(v) + e2[k] / v;
    }
    return -0.5 * sum;
  }
  // σβ² maximising ℓ at σ_t² (searched in log σβ² up to the all-bearing variance), and ℓ there.
  double Profiled(double jitter2, double* sigma2 = nullptr) const {
    const auto at = [&](double log_s2) { return LogLikelihood(std::exp(log_s2), jitter2); };
    const double top = std::log(mean_e2);
    const double best = GoldenMax(at, top - 25.0, top);
    if (sigma2 != nullptr) *sigma2 = std::exp(best);
    return at(best);
  }
};

}  // namespace

BearingJitterEstimate EstimateBearingJitter(const std::vector<double>& errors_rad,
                                            const std::vector<double>& rates_rad_per_s,
                                            double redundancy_fraction, double significance) {
  BearingJitterEstimate out;
  const double f = std::clamp(redundancy_fraction, 0.05, 1.0);
  std::vector<double> e2, g2;
  double sum_e2 = 0.0, sum_g2 = 0.0;
  for (size_t k = 0; k < errors_rad.size() && k < rates_rad_per_s.size(); ++k) {
    e2.push_back(errors_rad[k] * errors_rad[k] / f);
    g2.push_back(rates_rad_per_s[k] * rates_rad_per_s[k]);
    sum_e2 += e2.back();
    sum_g2 += g2.back();
  }
  out.bearings_used = static_cast<int>(e2.size());
  if (e2.size() < 3 || !(sum_e2 > 0.0) || !(sum_g2 > 0.0)) return out;
  const Profile profile{e2, g2, sum_e2 / e2.size()};
  double sigma2 = 0.0;
  const double at_zero = profile.Profiled(0.0, &sigma2);
  out.bearing_sigma_without_jitter_rad = out.bearing_sigma_rad = std::sqrt(sigma2);
  // The jitter that alone would explain every error: the search's end.
  const double top = 2.0 * std::sqrt(profile.mean_e2 / (sum_g2 / g2.size()));
  const auto at = [&](double jitter) { return profile.Profiled(jitter * jitter); };
  constexpr int kGrid = 41;
  int best = 0;
  double best_value = at_zero;
  for (int i = 1; i < kGrid; ++i) {
    const double value = at(top * i / (kGrid - 1));
    if (value > best_value) best = i, best_value = value;
  }
  if (best == 0) return out;
  const double step = top / (kGrid - 1);
  const double jitter = GoldenMax(at, std::max(0.0, (best - 1) * step), (best + 1) * step);
  const double value = at(jitter);
  out.lr_statistic = std::max(0.0, 2.0 * (value - at_zero));
  out.p_value = out.lr_statistic > 0.0 ? 0.5 * ChiSquareSurvival(out.lr_statistic, 1) : 1.0;
  out.significant = out.p_value <= significance;
  out.jitter_s = jitter;
  profile.Profiled(jitter * jitter, &sigma2);
  out.bearing_sigma_rad = std::sqrt(sigma2);
  // σ from the curvature of the profile, −1/ℓ''.
  const double h = std::max(1e-3 * jitter, 1e-4 * top);
  const double curvature = (at(jitter + h) - 2.0 * value + at(std::max(0.0, jitter - h))) / (h * h);
  out.jitter_stddev_s = curvature < 0.0 ? 1.0 / std::sqrt(-curvature) : 0.0;
  return out;
}

std::string BearingTimingTreatment(const BearingTiming& timing) {
  if (timing.clock_modelled) {
    return timing.jitter_modelled ? "free-running sensor clock and stamp jitter modelled"
                                  : "free-running sensor clock modelled";
  }
  if (timing.time_offset_modelled && timing.jitter_modelled) {
    return "clock offset and stamp jitter modelled";
  }
  if (timing.time_offset_modelled) return "clock offset modelled";
  if (timing.jitter_modelled) return "stamp jitter modelled";
  return "stamps as sample times";
}

std::string BearingTimingStatement(const BearingTiming& timing) {
  std::string text;
  if (timing.clock_modelled) {
    text = "The bearing sensor free-runs on its own clock (period " +
           Num(timing.clock.period_s * 1e3, 6) + " ± " +
           Num(timing.clock.period_stddev_s * 1e3, 2) + " ms, stamp steps " +
           Num(timing.clock.stamp_step_s * 1e3, 6) +
           " ms) and the logger stamped each bearing when it picked it up, up to a period late: "
           "the calibration takes each bearing at its sample time on that clock (" +
           std::to_string(timing.clock.skipped_samples) + " samples the logger missed";
    if (timing.held_bearings_dropped > 0) {
      text += ", " + std::to_string(timing.held_bearings_dropped) +
              " picked up twice, the repeats dropped";
    }
    if (timing.bearings_before_encoders > 0) {
      text += ", " + std::to_string(timing.bearings_before_encoders) +
              " bearings taken before their run's first encoder sample dropped";
    }
    text += "). The clock's phase is estimated with the calibration as a clock offset of " +
            Num(timing.time_offset_s * 1e3, 3) + " ± " + Num(timing.time_offset_stddev_s * 1e3, 2) +
            " ms.";
  } else if (timing.time_offset_modelled) {
    text = "The bearings were taken " + Num(std::abs(timing.time_offset_s) * 1e3, 3) + " ± " +
           Num(timing.time_offset_stddev_s * 1e3, 2) + " ms " +
           (timing.time_offset_s >= 0.0 ? "after" : "before") +
           " their stamps on the encoder clock (likelihood-ratio test p = " +
           Num(timing.time_offset_p_value, 2) + "); the calibration models that offset.";
  } else if (timing.time_offset_tested) {
    text = "No clock offset between bearings and encoders is evident (" +
           Num(timing.time_offset_free_s * 1e3, 3) + " ± " +
           Num(timing.time_offset_stddev_s * 1e3, 2) +
           " ms, p = " + Num(timing.time_offset_p_value, 2) +
           "); the bearing stamps are taken as sample times.";
  }
  if (timing.jitter_modelled) {
    text += (text.empty() ? "" : " ") + std::string("The bearing times scatter by ") +
            Num(timing.jitter.jitter_s * 1e3, 3) + " ± " +
            Num(timing.jitter.jitter_stddev_s * 1e3, 2) +
            " ms against the encoder clock (bearing or encoder stamps; p = " +
            Num(timing.jitter.p_value, 2) +
            "): each bearing is weighted by σβ² + σt²·(dβ/dt)², its rate from the model.";
  } else if (timing.jitter_tested) {
    text += (text.empty() ? "" : " ") +
            std::string("No stamp jitter of the bearings against the encoders is evident (p = ") +
            Num(timing.jitter.p_value, 2) + ").";
  }
  return text;
}

}  // namespace calib
