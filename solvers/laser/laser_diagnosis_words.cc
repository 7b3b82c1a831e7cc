#include <calib/core/text_format.h>
#include <calib/solvers/diagnosis/statement.h>
#include <calib/solvers/laser/laser_diagnosis_internal.h>
#include <calib/solvers/stats/change_point.h>

#include <algorithm>
#include <cmath>

namespace calib {
namespace laser_diagnosis {
namespace {

// A parameter counts as part of a confounding combination above this share of the effect.
constexpr double kConfoundingShare = 1e-3;

std::string EffectPhrase(const LaserFinding& f, double log_speed) {
  const double ms = 1000.0;
  switch (f.effect) {
    case LaserEffect::kTimeOffset:
      return Format(f.value >= 0 ? "The scans are stamped %.1f ± %.1f ms early relative to the "
                                   "encoders"
                                 : "The scans are stamped %.1f ± %.1f ms late relative to the "
                                   "encoders",
                    std::abs(f.value) * ms, f.stddev * ms);
    case LaserEffect::kLateralSlip:
      return Format("In turns the robot slides sideways at γ·v·ω with γ = %.1f ± %.1f ms",
                    f.value * ms, f.stddev * ms) +
             (f.value >= 0 ? " (toward the inside of the turn)"
                           : " (toward the outside of the turn)");
    case LaserEffect::kLongitudinalSlip:
      return Format(
          "The wheels slip along the track when the speed changes: forward velocity "
          "v − γ·dv/dt with γ = %.1f ± %.1f ms",
          f.value * ms, f.stddev * ms);
    case LaserEffect::kWheelRadiusChange: {
      return Format(
          "The wheel radii change at t = %.1f ± %.1f s from the start of the log, to "
          "r_l %.4f ± %.4f mm and r_r %.4f ± %.4f mm",
          f.value, f.stddev, f.r_l_after * 1e3, f.r_l_after_stddev * 1e3, f.r_r_after * 1e3,
          f.r_r_after_stddev * 1e3);
    }
    case LaserEffect::kSpeedDependentRadius:
      return Format(
                 "The effective wheel radius depends on the wheel speed, r·(1 + γ·(|φ| − %.2f "
                 "rad/s))",
                 log_speed) +
             Format(" with γ = %.3g ± %.2g s/rad", f.value, f.stddev) +
             Format(" (%+.2f %% per 0.1 rad/s)", 10.0 * f.value);
    case LaserEffect::kIcrOffset:
      return Format("The instantaneous centre of rotation sits %.1f ± %.1f mm ahead of the axle",
                    f.value * 1e3, f.stddev * 1e3);
    case LaserEffect::kScanScale:
      return Format("The scan matcher scales translations by 1 %+.2g ± %.2g", f.value, f.stddev);
  }
  return "";
}

std::string ConfoundedSentence(const LaserFinding& f) {
  std::string with;
  for (size_t i = 0; i < f.confounded_with.size(); ++i) {
    with +=
        (i > 0 ? (i + 1 == f.confounded_with.size() ? " and " : ", ") : "") + f.confounded_with[i];
  }
  if (f.effect == LaserEffect::kIcrOffset) {
    return "An offset of the instantaneous centre of rotation along x is exactly absorbed by " +
           with + ": this data cannot see it, so it is not a finding.";
  }
  if (f.effect == LaserEffect::kScanScale) {
    return "A scale error of the scan matcher is exactly absorbed by scaling " + with +
           " together: this data cannot see it, so it is not a finding.";
  }
  return "The " + f.name + " effect is exactly absorbed by " + with +
         ": this log cannot separate it, so it is not a finding.";
}

// Shifts in mm and degrees.
std::vector<ParamWords> LaserParamWords() {
  std::vector<ParamWords> words;
  for (const ParamInfo& info : kLaserParams) {
    words.push_back({info.name, info.display_scale,
                     info.is_angle ? std::string(" °") : std::string(" ") + info.display_unit});
  }
  return words;
}

// "a structure in the residuals that follows X" for a confirmed refit of implausible size.
std::string ImplausibleSentence(const LaserFinding& f, double log_speed) {
  const auto& names = LaserCovariateNames();
  const auto it = std::find(names.begin(), names.end(), f.follows);
  const std::string words =
      it != names.end() ? CovariateWords()[it - names.begin()] : std::string("wheel speed");
  return "A structure in the residuals that follows " + words + " (" +
         Format("score test %.1f, ", f.statistic) + PValueText(f.p_value) +
         Format("; the held-out cost falls by %.1f %%", 100.0 * f.heldout_reduction) +
         "): modelled as " + f.name + " it would need " + f.implausible_reason +
         ", a size the physics does not have, so it is not adopted as " + f.name +
         " — timing, the scan matcher or an effect outside the library may cause it (" +
         EffectPhrase(f, log_speed) + ").";
}

}  // namespace

std::string ImplausibleReason(const LaserEffectModel& model, const LaserPlausibility& bounds,
                              LaserEffect effect, double turn_rate, std::string* follows) {
  const LaserEffectInfo& info = EffectInfo(effect);
  const double g = model.gamma(info.offset);
  switch (effect) {
    case LaserEffect::kSpeedDependentRadius:
      *follows = "speed";
      if (std::abs(g) > bounds.speed_radius_per_rad_s) {
        return Format("a radius changing by %+.1f %% per 0.1 rad/s of wheel speed (bound ±%.1f %%)",
                      10.0 * g, 10.0 * bounds.speed_radius_per_rad_s);
      }
      break;
    case LaserEffect::kWheelRadiusChange: {
      *follows = "time";
      const double step = std::max(std::abs(g), std::abs(model.gamma(info.offset + 1)));
      if (step > bounds.radius_step) {
        return Format("a radius step of %+.1f %% / %+.1f %% (left / right; bound ±%.1f %%)",
                      100.0 * g, 100.0 * model.gamma(info.offset + 1), 100.0 * bounds.radius_step);
      }
      break;
    }
    case LaserEffect::kLateralSlip:
      *follows = "v_times_omega";
      if (std::abs(g) * turn_rate > bounds.lateral_slip_angle_rad) {
        return Format(
            "a slip angle γ·ω of %.2f rad at the log's turn rates (γ = %.0f ms, ω = "
            "%.2f rad/s; bound %.2f rad)",
            std::abs(g) * turn_rate, 1e3 * g, turn_rate, bounds.lateral_slip_angle_rad);
      }
      break;
    case LaserEffect::kLongitudinalSlip:
      *follows = "acceleration";
      if (std::abs(g) > bounds.longitudinal_slip_s) {
        return Format("a longitudinal slip coefficient of %.0f ms (bound %.0f ms)", 1e3 * g,
                      1e3 * bounds.longitudinal_slip_s);
      }
      break;
    default:
      break;
  }
  follows->clear();
  return "";
}

std::vector<std::string> ConfoundedWith(const ScoreTestResult& test, const RobustFitBlocks& blocks,
                                        const Eigen::MatrixXd& sensitivity,
                                        const std::vector<std::string>& names) {
  std::vector<std::string> with;
  const Eigen::Index n = blocks.residual.rows();
  const auto weighted_norm = [&](const Eigen::VectorXd& column) {
    double sum = 0.0;
    for (Eigen::Index k = 0; k < n; ++k) {
      sum += blocks.rho1(k) * column.segment<3>(3 * k).squaredNorm();
    }
    return std::sqrt(sum);
  };
  double total = 0.0;
  for (Eigen::Index j = 0; j < sensitivity.cols(); ++j) total += weighted_norm(sensitivity.col(j));
  if (!(total > 0.0)) return with;
  for (Eigen::Index i = 0; i < blocks.jacobian.cols(); ++i) {
    double share = 0.0;
    for (Eigen::Index j = 0; j < sensitivity.cols(); ++j) {
      share += weighted_norm(blocks.jacobian.col(i) * test.absorption(i, j));
    }
    if (share / total > kConfoundingShare) with.push_back(names[i]);
  }
  return with;
}

std::vector<std::string> FreeNames(const LaserEffectModel& model) {
  std::vector<std::string> names(kLaserParamNames.begin(), kLaserParamNames.end());
  for (LaserEffect effect : model.effects) {
    const LaserEffectInfo& info = EffectInfo(effect);
    for (int i = 0; i < info.size; ++i) {
      names.push_back(std::string(info.name) +
                      (info.size > 1 ? (i == 0 ? "_left" : "_right") : ""));
    }
  }
  return names;
}

std::string LaserStatement(const LaserFinding& f, double typical_wheel_speed) {
  if (f.implausible) return ImplausibleSentence(f, typical_wheel_speed);
  StatementWords words;
  words.base = "parameters";
  words.params = LaserParamWords();
  if (f.confounded) words.confounded = ConfoundedSentence(f);
  if (f.significant) words.adopted = EffectPhrase(f, typical_wheel_speed);
  if (f.effect == LaserEffect::kWheelRadiusChange) {
    words.estimate = Format("; the likeliest change time is t = %.1f s", f.value);
  } else if (f.stddev > 0.0) {
    words.estimate = "; one-step estimate " + Format("%.3g ± %.2g ", f.value, f.stddev) + f.unit;
  }
  const auto& names = LaserCovariateNames();
  const auto it = std::find(names.begin(), names.end(), f.location.covariate);
  if (it != names.end()) words.covariate = CovariateWords()[it - names.begin()];
  return WriteStatement(f, words);
}

const std::vector<std::string>& CovariateUnits() {
  static const std::vector<std::string> units = {"s", "m/s", "rad/s", "m/s²", "m/s²", "rad/s²"};
  return units;
}

const std::vector<std::string>& CovariateWords() {
  static const std::vector<std::string> words = {"time",
                                                 "forward speed",
                                                 "angular rate",
                                                 "v·ω (centripetal acceleration)",
                                                 "forward acceleration",
                                                 "angular acceleration"};
  return words;
}

}  // namespace laser_diagnosis

std::string LaserEffectName(LaserEffect effect) { return EffectInfo(effect).name; }

StatusOr<LaserEffect> ParseLaserEffect(const std::string& name) {
  for (int i = 0; i < kNumLaserEffects; ++i) {
    if (name == kLaserEffectInfo[i].name) return static_cast<LaserEffect>(i);
  }
  std::string known;
  for (int i = 0; i < kNumLaserEffects; ++i) {
    known += (i ? ", " : "") + std::string(kLaserEffectInfo[i].name);
  }
  return Status::InvalidInput("unknown effect '" + name + "' (known: " + known + ")");
}

std::vector<LaserEffect> AllLaserEffects() {
  std::vector<LaserEffect> all;
  for (int i = 0; i < kNumLaserEffects; ++i) all.push_back(static_cast<LaserEffect>(i));
  return all;
}

const std::vector<std::string>& LaserCovariateNames() {
  static const std::vector<std::string> names = {
      "time", "speed", "angular_rate", "v_times_omega", "acceleration", "angular_acceleration"};
  return names;
}

}  // namespace calib

namespace calib {
namespace {

FitReport ToFitReport(const LaserFitReport& fit) {
  FitReport out;
  for (LaserEffect effect : fit.effects) out.effects.push_back(LaserEffectName(effect));
  out.params.assign(std::begin(kLaserParams), std::end(kLaserParams));
  out.estimate = fit.estimate.ToVector();
  out.stddev = fit.stddev;
  out.rms = fit.rms;
  out.rms_units = {"m", "m", "rad"};
  out.robust_cost = fit.robust_cost;
  out.inliers = fit.inliers;
  if (fit.stamp_jitter_s > 0.0) {
    // A timing model of this fit (each interval whitened by its own covariance).
    out.effects.insert(out.effects.begin(), "stamp_jitter");
    EffectValue value;
    value.name = "stamp_jitter";
    value.value = fit.stamp_jitter_s;
    value.stddev = fit.stamp_jitter_stddev_s;
    value.unit = "s";
    out.effect_values.push_back(value);
  }
  for (LaserEffect effect : fit.effects) {
    const LaserEffectInfo& info = EffectInfo(effect);
    EffectValue value;
    value.name = info.name;
    if (effect == LaserEffect::kWheelRadiusChange) {
      value.value = fit.change_time_s;
      value.stddev = fit.change_time_stddev_s;
      value.unit = "s";
      value.gamma = fit.gamma.segment<2>(info.offset);
      value.gamma_stddev = fit.gamma_stddev.segment<2>(info.offset);
    } else {
      value.value = fit.gamma(info.offset);
      value.stddev = fit.gamma_stddev(info.offset);
      value.unit = info.unit;
    }
    out.effect_values.push_back(value);
  }
  out.words.emplace_back("boundary_speeds", fit.boundary == BoundarySpeedModel::kSmooth
                                                ? "smooth"
                                                : "piecewise_constant");
  return out;
}

}  // namespace

DiagnosisReport ToDiagnosisReport(const LaserDiagnosis& diagnosis) {
  DiagnosisReport out;
  out.problem = "laser";
  out.units = "m, rad, s";
  out.steps = diagnosis.steps;
  CopyCommonFields(diagnosis, &out);
  out.params.assign(std::begin(kLaserParams), std::end(kLaserParams));
  out.baseline = ToFitReport(diagnosis.baseline);
  out.final_fit = ToFitReport(diagnosis.final_fit);
  for (const Finding& f : diagnosis.timing_findings) {
    if (f.significant) out.findings.push_back(ReportedFinding{f, {}});
  }
  for (const LaserFinding& f : diagnosis.findings) {
    ReportedFinding reported{f, {}};
    if (f.effect == LaserEffect::kWheelRadiusChange && f.testable()) {
      reported.extra = {{"r_l_after", f.r_l_after},
                        {"r_r_after", f.r_r_after},
                        {"r_l_after_stddev", f.r_l_after_stddev},
                        {"r_r_after_stddev", f.r_r_after_stddev}};
    }
    out.findings.push_back(reported);
  }
  for (const Finding& f : diagnosis.timing_findings) {
    if (!f.significant) out.findings.push_back(ReportedFinding{f, {}});
  }
  out.adopted = diagnosis.adopted_timing;
  for (LaserEffect effect : diagnosis.adopted) out.adopted.push_back(LaserEffectName(effect));
  return out;
}

}  // namespace calib
