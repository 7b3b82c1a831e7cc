#include <calib/solvers/laser/laser_diagnosis.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>
#include <optional>

#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/stats/change_point.h>
#include <calib/solvers/stats/score_test.h>

namespace calib {
namespace {

constexpr double kInlierChi2 = 16.27;  // χ²₃ at 99.9 %, as CalibrateLaser.
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// A parameter counts as part of a confounding combination above this share of the effect.
constexpr double kConfoundingShare = 1e-3;

std::string Format(const char* format, double a) {
  char text[128];
  std::snprintf(text, sizeof(text), format, a);
  return text;
}
std::string Format(const char* format, double a, double b) {
  char text[128];
  std::snprintf(text, sizeof(text), format, a, b);
  return text;
}

// Display units of the base parameters: mm and degrees.
double ParamScale(int i) { return i == 5 ? 180.0 / M_PI : 1000.0; }
const char* ParamUnit(int i) { return i == 5 ? "°" : "mm"; }

bool UsesBoundarySpeeds(LaserEffect effect) {
  return effect == LaserEffect::kTimeOffset || effect == LaserEffect::kLongitudinalSlip;
}

// Everything the steps share.
struct Context {
  const std::vector<LaserInterval>* intervals = nullptr;
  const LaserDiagnosisOptions* options = nullptr;
  const LaserEffectData* data = nullptr;
  double log_start_s = 0.0;
  std::vector<std::vector<bool>> train_masks;  // Per held-out block: the training intervals.
  std::vector<std::vector<bool>> test_masks;
};

struct HeldOut {
  double cost = 0.0;
  double sum_s = 0.0;  // Σ s over held-out inliers.
  int count = 0;
  double rms() const { return count > 0 ? std::sqrt(sum_s / (3.0 * count)) : 0.0; }
};

// Fits `model` on each training set and evaluates it on the held-out block.
StatusOr<HeldOut> CrossValidate(const Context& context, const LaserEffectModel& model,
                                const LaserCalibration& initial) {
  HeldOut held_out;
  for (size_t f = 0; f < context.train_masks.size(); ++f) {
    const StatusOr<LaserEffectFit> fit =
        FitLaserEffects(*context.data, model, initial, &context.train_masks[f]);
    if (!fit.ok()) return fit.status();
    const LaserEffectEvaluation evaluation =
        EvaluateLaserEffects(*context.data, fit->model, fit->calibration, false);
    held_out.cost += evaluation.Cost(&context.test_masks[f]);
    for (Eigen::Index k = 0; k < evaluation.residual.rows(); ++k) {
      if (!context.test_masks[f][k]) continue;
      const double s = evaluation.residual.row(k).squaredNorm();
      if (s < kInlierChi2) {
        held_out.sum_s += s;
        ++held_out.count;
      }
    }
  }
  return held_out;
}

// The loss's scale factor of likelihood-ratio statistics: 2·Δ(½Σρ)/κ is χ² under the null,
// κ = mean(ρ'²·s)/3 / mean(ρ' + 2ρ''·s/3) (1 for Gaussian residuals without a robust loss).
double LikelihoodRatioScale(const LaserEffectEvaluation& evaluation) {
  double meat = 0.0, bread = 0.0;
  const Eigen::Index n = evaluation.residual.rows();
  for (Eigen::Index k = 0; k < n; ++k) {
    const double s = evaluation.residual.row(k).squaredNorm();
    meat += evaluation.rho1(k) * evaluation.rho1(k) * s / 3.0;
    bread += evaluation.rho1(k) + 2.0 * evaluation.rho2(k) * s / 3.0;
  }
  return bread > 0.0 && meat > 0.0 ? meat / bread : 1.0;
}

std::vector<int> EffectColumns(LaserEffect effect) {
  const LaserEffectInfo& info = EffectInfo(effect);
  std::vector<int> columns;
  for (int i = 0; i < info.size; ++i) columns.push_back(kNumLaserParams + info.offset + i);
  return columns;
}

// The change time by the profile likelihood: refits with the change at 24 boundaries spread over
// the searched range and at the 6 boundaries on either side of the scan's estimate, then at
// sub-steps of the intervals next to the best boundary. The interval inverts the profile:
// at the true time the drop D = 2·(log L_max − log L) is 2·max(M_l, M_r), M_l, M_r independent
// Exp(1) (the sup of W(s) − s/2 on each side; Yao 1987), so P(D ≤ q) = (1 − e^{−q/2})² and the
// 68.3 % set is where the drop is ≤ 3.50. Its half-width is the 68 % quantile of |error|;
// in the limiting law (argmax of W(s) − |s|/2: quantile 2.9, standard deviation √26 = 5.1) the
// standard deviation is 1.75 times that, which is what is reported.
struct ChangeLocation {
  LaserEffectFit fit;
  double stddev_s = 0.0;
};
ChangeLocation LocateChange(const LaserEffectData& data,
                            const std::vector<LaserInterval>& intervals, const LaserEffectFit& fit,
                            const LaserDiagnosisOptions& options) {
  constexpr int kCoarse = 24;
  constexpr int kBoundaryWindow = 6;
  constexpr double kDrop68 = 3.50;             // (1 − e^{−q/2})² = 0.683.
  constexpr double kStddevPerQuantile = 1.75;  // √26 / 2.9.
  const size_t n = intervals.size();
  ChangeLocation best{fit, 0.0};
  std::map<double, double> profile;  // Change time → cost.
  profile[fit.model.change_time_s] = fit.cost;
  const LaserEffectFit start = fit;
  const auto trial = [&](double t) {
    if (profile.count(t)) return;
    LaserEffectModel model = start.model;
    model.change_time_s = t;
    const StatusOr<LaserEffectFit> trial_fit = FitLaserEffects(data, model, start.calibration);
    if (!trial_fit.ok()) return;
    profile[t] = trial_fit->cost;
    if (trial_fit->cost < best.fit.cost) best.fit = *trial_fit;
  };
  const auto index_of = [&](double t) {
    size_t index = 0;
    while (index + 1 < n && intervals[index].start_s < t) ++index;
    return index;
  };
  const double trim = std::clamp(options.change_trim, 0.0, 0.49);
  const size_t lo = std::max<size_t>(1, static_cast<size_t>(std::ceil(trim * n)));
  const size_t hi = std::min(n - 1, static_cast<size_t>(std::floor((1.0 - trim) * n)));
  for (int g = 0; g <= kCoarse && hi > lo; ++g)
    trial(intervals[lo + (hi - lo) * g / kCoarse].start_s);
  const size_t index = index_of(fit.model.change_time_s);
  for (size_t j = index > kBoundaryWindow ? index - kBoundaryWindow : 1;
       j <= std::min(n - 1, index + kBoundaryWindow); ++j) {
    trial(intervals[j].start_s);
  }
  // Around the best boundary: its neighbours, then sub-steps.
  size_t best_index = index_of(best.fit.model.change_time_s);
  for (size_t j = best_index > kBoundaryWindow ? best_index - kBoundaryWindow : 1;
       j <= std::min(n - 1, best_index + kBoundaryWindow); ++j) {
    trial(intervals[j].start_s);
  }
  best_index = index_of(best.fit.model.change_time_s);
  const int steps = std::max(1, options.change_profile_steps);
  const double boundary = intervals[best_index].start_s;
  for (int s = -steps + 1; s < steps; ++s) {
    const LaserInterval& in =
        s < 0 && best_index > 0 ? intervals[best_index - 1] : intervals[best_index];
    trial(boundary + in.duration_s * s / steps);
  }
  // The 68.3 % set: every profiled time whose drop is ≤ 3.5 (the profile is a random walk, the
  // set need not be connected); its hull, each end interpolated to the next time outside.
  const double kappa =
      LikelihoodRatioScale(EvaluateLaserEffects(data, best.fit.model, best.fit.calibration, false));
  const auto drop = [&](double cost) { return 2.0 * (cost - best.fit.cost) / kappa; };
  std::vector<std::pair<double, double>> points(profile.begin(), profile.end());
  size_t first = points.size(), last = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (drop(points[i].second) <= kDrop68) {
      first = std::min(first, i);
      last = std::max(last, i);
    }
  }
  const auto edge = [&](size_t inside, size_t outside) {
    const double d_in = drop(points[inside].second), d_out = drop(points[outside].second);
    const double f = d_out > d_in ? (kDrop68 - d_in) / (d_out - d_in) : 0.0;
    return points[inside].first + f * (points[outside].first - points[inside].first);
  };
  const double left = first > 0 ? edge(first, first - 1) : points[first].first;
  const double right = last + 1 < points.size() ? edge(last, last + 1) : points[last].first;
  const double grid = intervals[best_index].duration_s / steps;
  best.stddev_s = std::max(kStddevPerQuantile * 0.5 * (right - left), grid / std::sqrt(12.0));
  return best;
}

RobustFitBlocks Blocks(const LaserEffectEvaluation& evaluation, const std::vector<int>& columns) {
  RobustFitBlocks blocks;
  blocks.residual = evaluation.residual;
  blocks.jacobian = SelectColumns(evaluation.jacobian, columns);
  blocks.rho1 = evaluation.rho1;
  blocks.rho2 = evaluation.rho2;
  return blocks;
}

// The model with `effect` added (γ initial values from `gamma`, the change time when needed).
LaserEffectModel WithEffect(const LaserEffectModel& model, LaserEffect effect,
                            const Eigen::VectorXd& gamma, double change_time_s) {
  LaserEffectModel next = model;
  next.effects.push_back(effect);
  const LaserEffectInfo& info = EffectInfo(effect);
  for (int i = 0; i < info.size; ++i) next.gamma(info.offset + i) = gamma(i);
  if (effect == LaserEffect::kWheelRadiusChange) next.change_time_s = change_time_s;
  return next;
}

// The per-interval unwhitened errors e = L⁻¹·r.
Eigen::MatrixXd Unwhitened(const LaserEffectData& data, const Eigen::MatrixXd& residual) {
  const Eigen::Matrix3d inverse = data.sqrt_information().inverse();
  return residual * inverse.transpose();
}

LaserFitReport MakeReport(const Context& context, const LaserEffectFit& fit,
                          const LaserEffectEvaluation& evaluation, double change_stddev_s) {
  LaserFitReport report;
  report.effects = fit.model.effects;
  report.estimate = fit.calibration;
  report.gamma = fit.model.gamma;
  report.boundary = fit.model.boundary;
  report.robust_cost = evaluation.Cost();
  if (fit.model.Has(LaserEffect::kWheelRadiusChange)) {
    report.change_time_s = fit.model.change_time_s - context.log_start_s;
    report.change_time_stddev_s = change_stddev_s;
  }
  const std::vector<int> columns = fit.model.FreeColumns();
  const StatusOr<Eigen::MatrixXd> covariance =
      LaserEffectCovariance(evaluation, columns, context.options->hac_lag);
  if (covariance.ok()) {
    for (size_t i = 0; i < columns.size(); ++i) {
      const double sigma = std::sqrt(std::max(0.0, (*covariance)(i, i)));
      if (columns[i] < kNumLaserParams) {
        report.stddev(columns[i]) = sigma;
      } else {
        report.gamma_stddev(columns[i] - kNumLaserParams) = sigma;
      }
    }
  }
  const Eigen::MatrixXd errors = Unwhitened(*context.data, evaluation.residual);
  Eigen::Vector3d sum_sq = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < errors.rows(); ++k) {
    if (evaluation.residual.row(k).squaredNorm() < kInlierChi2) {
      sum_sq += errors.row(k).transpose().cwiseAbs2();
      ++report.inliers;
    }
  }
  if (report.inliers > 0) report.rms = (sum_sq / report.inliers).cwiseSqrt();
  return report;
}

// Per-interval covariates from the baseline calibration (see LaserCovariateNames).
std::vector<std::vector<double>> Covariates(const Context& context,
                                            const LaserCalibration& calibration) {
  const std::vector<LaserInterval>& intervals = *context.intervals;
  LaserEffectModel smooth;
  smooth.boundary = BoundarySpeedModel::kSmooth;
  const std::vector<LaserEffectContext> contexts = context.data->Contexts(smooth);
  const double rl = calibration.odometry.left_radius_m, rr = calibration.odometry.right_radius_m;
  const double b = calibration.odometry.wheelbase_m;
  const auto v_of = [&](const Eigen::Vector2d& phi) { return 0.5 * (rl * phi(0) + rr * phi(1)); };
  const auto w_of = [&](const Eigen::Vector2d& phi) { return (rr * phi(1) - rl * phi(0)) / b; };
  std::vector<std::vector<double>> covariates(6, std::vector<double>(intervals.size()));
  for (size_t k = 0; k < intervals.size(); ++k) {
    const LaserInterval& in = intervals[k];
    const Eigen::Vector2d phi(in.left_speed, in.right_speed);
    const double v = v_of(phi), w = w_of(phi);
    const LaserEffectContext& c = contexts[k];
    covariates[0][k] = in.start_s + 0.5 * in.duration_s - context.log_start_s;
    covariates[1][k] = v;
    covariates[2][k] = w;
    covariates[3][k] = v * w;
    covariates[4][k] = (v_of(c.end.after) - v_of(c.start.before)) / in.duration_s;
    covariates[5][k] = (w_of(c.end.after) - w_of(c.start.before)) / in.duration_s;
  }
  return covariates;
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

// A covariate profile of before/after residuals; `along` adds the residual projected on a signal.
CovariateProfile Profile(const std::string& name, const std::string& unit,
                         const std::vector<double>& covariate, const Eigen::MatrixXd& before,
                         const Eigen::VectorXd& before_weight, const Eigen::MatrixXd& after,
                         const Eigen::VectorXd& after_weight, int bins) {
  CovariateProfile profile;
  profile.name = name;
  profile.unit = unit;
  const BinnedMeans b = BinByCovariate(covariate, before, before_weight, bins);
  const BinnedMeans a = BinByCovariate(covariate, after, after_weight, bins);
  const BinnedMeans b3 = BinByCovariate(covariate, before.leftCols(3), before_weight, bins);
  const BinnedMeans a3 = BinByCovariate(covariate, after.leftCols(3), after_weight, bins);
  profile.center = b.center;
  profile.before_mean = b.mean;
  profile.before_stderr = b.standard_error;
  profile.after_mean = a.mean;
  profile.after_stderr = a.standard_error;
  profile.before_statistic = b3.statistic;
  profile.after_statistic = a3.statistic;
  profile.before_p_value = b3.p_value;
  profile.after_p_value = a3.p_value;
  profile.dof = b3.dof;
  return profile;
}

// Residual structure of a fit: Holm over the covariates' binned-mean tests and the time
// change-point test of the weighted whitened residuals.
ResidualStructure Structure(const Context& context,
                            const std::vector<std::vector<double>>& covariates,
                            const LaserEffectEvaluation& evaluation) {
  ResidualStructure structure;
  const Eigen::Index n = evaluation.residual.rows();
  Eigen::MatrixXd weighted(n, 3);
  for (Eigen::Index k = 0; k < n; ++k) {
    weighted.row(k) = std::sqrt(evaluation.rho1(k)) * evaluation.residual.row(k);
  }
  std::vector<std::pair<double, int>> tests;  // (p, covariate index; −1 the change point)
  for (size_t c = 0; c < covariates.size(); ++c) {
    const BinnedMeans binned = BinByCovariate(covariates[c], evaluation.residual, evaluation.rho1,
                                              context.options->covariate_bins);
    tests.push_back({binned.p_value, static_cast<int>(c)});
  }
  size_t split = 0;
  structure.change_p_value = ConstantMeanPValue(weighted, context.options->change_trim, &split);
  tests.push_back({structure.change_p_value, -1});
  std::sort(tests.begin(), tests.end());
  const double alpha = context.options->alpha;
  const size_t m = tests.size();
  std::vector<bool> rejected(m, false);
  for (size_t i = 0; i < m; ++i) {
    if (tests[i].first > alpha / (m - i)) break;
    rejected[i] = true;
  }
  for (size_t i = 0; i < m; ++i) {
    if (tests[i].second >= 0) {
      // The most significant covariate (tests are sorted), named only when significant.
      if (structure.p_value == 1.0 && structure.covariate.empty()) {
        structure.p_value = tests[i].first;
        if (rejected[i]) structure.covariate = LaserCovariateNames()[tests[i].second];
      }
    } else if (rejected[i] && split > 0) {
      structure.change_time_s = (*context.intervals)[split].start_s - context.log_start_s;
    }
  }
  structure.found = rejected[0];
  if (!structure.found) {
    structure.statement =
        "No structure is left in the residuals against time, speed, angular "
        "rate, v·ω or the accelerations (smallest " +
        PValueText(tests[0].first) + ", family-wise level " + Format("%.2g", alpha) + ").";
    return structure;
  }
  std::string text = "The residuals still depend on ";
  if (!structure.covariate.empty()) {
    const auto& names = LaserCovariateNames();
    const size_t index = std::find(names.begin(), names.end(), structure.covariate) - names.begin();
    text += CovariateWords()[index] + " (binned means, " + PValueText(structure.p_value) + ")";
  }
  if (structure.change_time_s >= 0.0) {
    if (!structure.covariate.empty()) text += " and ";
    text += "their mean changes at t = " + Format("%.1f s", structure.change_time_s) + " (" +
            PValueText(structure.change_p_value) + ")";
  }
  structure.statement = text + ": a mismatch that the adopted model does not explain.";
  return structure;
}

// One candidate's state across the steps.
struct CandidateState {
  LaserEffect effect;
  LaserFinding finding;
  ScoreTestResult test;
  double change_time_s = kInfinity;  // Located change (on the log clock).
  bool done = false;                 // Adopted or confounded.
  bool rejected_on_confirmation = false;
};

std::vector<std::string> ConfoundedWith(const ScoreTestResult& test, const RobustFitBlocks& blocks,
                                        const Eigen::MatrixXd& sensitivity,
                                        const std::vector<std::string>& names) {
  std::vector<std::string> with;
  const Eigen::Index n = blocks.residual.rows();
  const auto weighted_norm = [&](const Eigen::VectorXd& column) {
    double sum = 0.0;
    for (Eigen::Index k = 0; k < n; ++k)
      sum += blocks.rho1(k) * column.segment<3>(3 * k).squaredNorm();
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

// Names of the free parameters of a model (base parameters, then effect entries).
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

// Shift of base parameters in words: the largest one or two in units of their sigmas.
std::string ShiftWords(const LaserParamVector& shift, const LaserParamVector& sigmas) {
  std::vector<int> order(kNumLaserParams);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return std::abs(sigmas(a)) > std::abs(sigmas(b)); });
  std::string text;
  for (int rank = 0; rank < 2; ++rank) {
    const int i = order[rank];
    if (rank > 0 && std::abs(sigmas(i)) < 1.0) break;
    if (rank > 0) text += " and ";
    char part[128];
    std::snprintf(part, sizeof(part), "%s %+.3g %s (%.1f σ)", kLaserParamNames[i].c_str(),
                  shift(i) * ParamScale(i), ParamUnit(i), std::abs(sigmas(i)));
    text += part;
  }
  return text;
}

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
      char text[256];
      std::snprintf(text, sizeof(text),
                    "The wheel radii change at t = %.1f ± %.1f s from the start of the log, to "
                    "r_l %.4f ± %.4f mm and r_r %.4f ± %.4f mm",
                    f.value, f.stddev, f.r_l_after * 1e3, f.r_l_after_stddev * 1e3,
                    f.r_r_after * 1e3, f.r_r_after_stddev * 1e3);
      return text;
    }
    case LaserEffect::kSpeedDependentRadius:
      return Format(
                 "The effective wheel radius depends on the wheel speed, r·(1 + γ·(|φ| − %.2f "
                 "rad/s))",
                 log_speed) +
             Format(" with γ = %.3g ± %.2g s/rad", f.value, f.stddev) +
             Format(" (%+.2f %% per 0.1 rad/s)", 10.0 * f.value, 0.0);
    case LaserEffect::kIcrOffset:
      return Format("The instantaneous centre of rotation sits %.1f ± %.1f mm ahead of the axle",
                    f.value * 1e3, f.stddev * 1e3);
    case LaserEffect::kScanScale:
      return Format("The scan matcher scales translations by 1 %+.2g ± %.2g", f.value, f.stddev);
  }
  return "";
}

void WriteStatement(LaserFinding* f, double typical_wheel_speed) {
  if (f->no_information) {
    f->statement = "The log's motion does not excite " + f->name +
                   " at all (no sensitivity): it can be neither found nor excluded.";
    return;
  }
  if (f->confounded) {
    std::string with;
    for (size_t i = 0; i < f->confounded_with.size(); ++i) {
      with += (i > 0 ? (i + 1 == f->confounded_with.size() ? " and " : ", ") : "") +
              f->confounded_with[i];
    }
    if (f->effect == LaserEffect::kIcrOffset) {
      f->statement =
          "An offset of the instantaneous centre of rotation along x is exactly "
          "absorbed by " +
          with + ": this data cannot see it, so it is not a finding.";
    } else if (f->effect == LaserEffect::kScanScale) {
      f->statement = "A scale error of the scan matcher is exactly absorbed by scaling " + with +
                     " together: this data cannot see it, so it is not a finding.";
    } else {
      f->statement = "The " + f->name + " effect is exactly absorbed by " + with +
                     ": this log cannot separate it, so it is not a finding.";
    }
    return;
  }
  char tested[256];
  std::snprintf(tested, sizeof(tested),
                "score test %.1f, %s, %.0f %% of it absorbable by the base "
                "parameters",
                f->statistic, PValueText(f->p_value).c_str(),
                100.0 * std::max(0.0, f->concealment));
  if (f->significant) {
    char hidden[256];
    std::snprintf(hidden, sizeof(hidden),
                  "score test %.1f, %s, %.0f %% of it hidden by the base "
                  "parameters",
                  f->statistic, PValueText(f->p_value).c_str(), 100.0 * f->absorbed_share);
    std::string text = EffectPhrase(*f, typical_wheel_speed) + " (" + hidden + ")";
    text += "; the base fit had absorbed it as " + ShiftWords(f->base_shift, f->base_shift_sigmas);
    text += Format("; modelling it cuts the held-out residual cost by %.1f %%",
                   100.0 * f->heldout_reduction);
    if (!f->location.covariate.empty()) {
      const auto& names = LaserCovariateNames();
      const size_t index =
          std::find(names.begin(), names.end(), f->location.covariate) - names.begin();
      text += "; it follows " + CovariateWords()[index];
      text += WindowWords(f->location);
    }
    f->statement = text + ".";
    return;
  }
  std::string text = "No " + f->name + " adopted: " + tested;
  if (f->effect == LaserEffect::kWheelRadiusChange) {
    text += Format("; the likeliest change time is t = %.1f s", f->value);
  } else if (f->stddev > 0.0) {
    text += "; one-step estimate " + Format("%.3g ± %.2g ", f->value, f->stddev) + f->unit;
  }
  if (f->refitted) {
    if (f->lr_p_value > f->holm_level) {
      text += "; the likelihood-ratio test did not confirm it (" + PValueText(f->lr_p_value) + ")";
    } else {
      text += Format("; the held-out blocks did not confirm it (held-out cost %+.2f %%)",
                     -100.0 * f->heldout_reduction);
    }
  }
  f->statement = text + ".";
}

}  // namespace

std::string LaserEffectName(LaserEffect effect) { return EffectInfo(effect).name; }

StatusOr<LaserEffect> ParseLaserEffect(const std::string& name) {
  for (int i = 0; i < kNumLaserEffects; ++i) {
    if (name == kLaserEffectInfo[i].name) return static_cast<LaserEffect>(i);
  }
  std::string known;
  for (int i = 0; i < kNumLaserEffects; ++i)
    known += (i ? ", " : "") + std::string(kLaserEffectInfo[i].name);
  return Status::Error("unknown effect '" + name + "' (known: " + known + ")");
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

StatusOr<LaserDiagnosis> DiagnoseLaser(const std::vector<LaserInterval>& intervals,
                                       const LaserDiagnosisOptions& options) {
  const auto start_time = std::chrono::steady_clock::now();
  const auto report = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  const Status valid = ValidateLaserIntervals(intervals);
  if (!valid.ok()) return valid;
  if (intervals.size() < 50) {
    return Status::Error("diagnosis needs at least 50 intervals (the log has " +
                         std::to_string(intervals.size()) + ")");
  }
  const size_t n = intervals.size();

  // 1. The robust base fit, whitened by its robust noise level.
  const StatusOr<LaserCalibrationResult> base = CalibrateLaser(intervals, options.calibration);
  if (!base.ok()) return base.status();
  std::vector<Eigen::Vector3d> errors(n);
  {
    const LaserParamVector v = base->estimate.ToVector();
    for (size_t k = 0; k < n; ++k) {
      errors[k] = LaserResidual::Error(intervals[k], v.data(), v.data() + 3);
    }
  }
  const Eigen::Vector3d sigma =
      options.calibration.noise_sigma ? *options.calibration.noise_sigma : RobustNoiseSigma(errors);
  const Eigen::Matrix3d sqrt_information = sigma.cwiseInverse().asDiagonal();
  const LaserEffectData data(intervals, sqrt_information, options.calibration.refinement);

  Context context;
  context.intervals = &intervals;
  context.options = &options;
  context.data = &data;
  context.log_start_s = intervals.front().start_s;
  const int blocks = std::clamp(options.cv_blocks, 2, 20);
  for (int f = 0; f < blocks; ++f) {
    std::vector<bool> test(n, false);
    for (size_t k = n * f / blocks; k < n * (f + 1) / blocks; ++k) test[k] = true;
    std::vector<bool> train(n);
    for (size_t k = 0; k < n; ++k) train[k] = !test[k];
    context.test_masks.push_back(test);
    context.train_masks.push_back(train);
  }

  LaserEffectModel model;
  model.boundary = options.boundary == BoundaryChoice::kPiecewiseConstant
                       ? BoundarySpeedModel::kPiecewiseConstant
                       : BoundarySpeedModel::kSmooth;
  StatusOr<LaserEffectFit> base_fit = FitLaserEffects(data, model, base->estimate);
  if (!base_fit.ok()) return base_fit.status();
  LaserEffectFit current = *base_fit;
  const LaserEffectEvaluation base_evaluation =
      EvaluateLaserEffects(data, current.model, current.calibration);

  LaserDiagnosis diagnosis;
  diagnosis.samples = static_cast<int>(n);
  diagnosis.baseline = MakeReport(context, current, base_evaluation, 0.0);
  report("base fit: cost " + Format("%.1f", current.cost));

  std::vector<CandidateState> candidates;
  for (LaserEffect effect : options.candidates) {
    if (std::any_of(candidates.begin(), candidates.end(),
                    [&](const CandidateState& c) { return c.effect == effect; })) {
      continue;
    }
    CandidateState state;
    state.effect = effect;
    state.finding.effect = effect;
    state.finding.name = LaserEffectName(effect);
    state.finding.unit = effect == LaserEffect::kWheelRadiusChange ? "s" : EffectInfo(effect).unit;
    candidates.push_back(state);
  }

  struct Adoption {
    LaserEffect effect;
    LaserParamVector shift;
    Eigen::MatrixXd signal;         // Whitened residual change (N × 3) at the adoption.
    Eigen::VectorXd contributions;  // Score contributions over time.
    double absorbed_share = 0.0;    // Of the fitted effect's signal, hidden by the base fit.
  };
  std::vector<Adoption> adoptions;
  double change_stddev_s = 0.0;
  std::optional<HeldOut> current_held_out;

  for (int step = 1; step <= kNumLaserEffects + 1; ++step) {
    // With max_effects reached the candidates are still tested (step 1 always), not refitted.
    const bool may_adopt = static_cast<int>(adoptions.size()) < options.max_effects;
    if (!may_adopt && step > 1) break;
    diagnosis.steps = step;
    // 2. Score tests of the remaining candidates at the current fit. A radius change that is
    // not modelled yet is evaluated with every interval after it (its Jacobian columns then
    // hold the sensitivity R_k of a change before interval k).
    LaserEffectModel evaluation_model = current.model;
    if (!current.model.Has(LaserEffect::kWheelRadiusChange)) {
      evaluation_model.change_time_s = -kInfinity;
    }
    const LaserEffectEvaluation evaluation =
        EvaluateLaserEffects(data, evaluation_model, current.calibration);
    const std::vector<int> nuisance = current.model.FreeColumns();
    const RobustFitBlocks fit_blocks = Blocks(evaluation, nuisance);
    const ScoreTester tester(fit_blocks, options.hac_lag);
    if (!tester.ok()) return Status::Error("the fit's information matrix is singular");
    const std::vector<std::string> nuisance_names = FreeNames(current.model);

    std::vector<CandidateState*> testable;
    for (CandidateState& c : candidates) {
      if (c.done) continue;
      const Eigen::MatrixXd sensitivity =
          SelectColumns(evaluation.jacobian, EffectColumns(c.effect));
      LaserFinding& f = c.finding;
      f.step = step;
      if (c.effect == LaserEffect::kWheelRadiusChange) {
        const ScoreTester::ChangeScan scan = tester.ScanChange(sensitivity, options.change_trim);
        c.test = scan.at_best;
        c.test.p_value = scan.p_value;
        c.change_time_s = intervals[scan.location].start_s;
      } else {
        c.test = tester.Test(sensitivity);
      }
      f.statistic = c.test.statistic;
      f.dof = c.test.dof;
      f.p_value = c.test.p_value;
      f.concealment = c.test.concealment;
      f.one_step = c.test.gamma;
      f.one_step_stddev = c.test.gamma_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
      f.absorbed = c.test.absorbed.head<kNumLaserParams>();
      if (!c.test.identifiable) {
        if (std::isnan(c.test.concealment)) {
          f.no_information = true;
        } else {
          f.confounded = true;
          f.confounded_with = ConfoundedWith(c.test, fit_blocks, sensitivity, nuisance_names);
        }
        c.done = true;
        continue;
      }
      testable.push_back(&c);
    }
    if (testable.empty()) break;

    // 3. Holm's step-down over the testable candidates.
    std::sort(testable.begin(), testable.end(),
              [](const CandidateState* a, const CandidateState* b) {
                return a->test.p_value < b->test.p_value;
              });
    const size_t m = testable.size();
    std::vector<CandidateState*> passing;
    bool stopped = false;
    for (size_t i = 0; i < m; ++i) {
      LaserFinding& f = testable[i]->finding;
      f.holm_level = options.alpha / (m - i);
      f.score_significant = !stopped && f.p_value <= f.holm_level;
      if (f.score_significant) {
        passing.push_back(testable[i]);
      } else {
        stopped = true;
      }
    }
    report("step " + std::to_string(step) + ": " + std::to_string(passing.size()) +
           " candidate(s) pass the score test");

    bool adopted = false;
    if (!may_adopt) passing.clear();
    for (CandidateState* c : passing) {
      LaserFinding& f = c->finding;
      // Refit with the candidate (both boundary models when it uses them and none is fixed).
      std::vector<BoundarySpeedModel> boundaries = {current.model.boundary};
      if (options.boundary == BoundaryChoice::kAuto && UsesBoundarySpeeds(c->effect)) {
        boundaries = {BoundarySpeedModel::kSmooth, BoundarySpeedModel::kPiecewiseConstant};
      }
      std::vector<LaserEffectFit> fits;
      double change_sigma = 0.0;
      for (BoundarySpeedModel boundary : boundaries) {
        // From γ = 0: the one-step value can be far off where the model is far from linear.
        LaserEffectModel next = WithEffect(current.model, c->effect,
                                           Eigen::VectorXd::Zero(c->test.dof), c->change_time_s);
        next.boundary = boundary;
        StatusOr<LaserEffectFit> fit = FitLaserEffects(data, next, current.calibration);
        if (!fit.ok()) continue;
        if (c->effect == LaserEffect::kWheelRadiusChange) {
          const ChangeLocation located = LocateChange(data, intervals, *fit, options);
          *fit = located.fit;
          change_sigma = located.stddev_s;
        }
        fits.push_back(*fit);
      }
      std::optional<LaserEffectFit> best;
      if (fits.size() == 2) {
        // The piecewise model's one-sided speeds add a |δ|·h term at speed jumps, which can fit
        // other mismatches there. It is preferred when it fits better and passes a score test
        // of ε = 0 (the coefficient of h equal to |δ|, not freely chosen).
        bool consistent = true;
        if (fits[1].model.Has(LaserEffect::kTimeOffset)) {
          const LaserEffectEvaluation at =
              EvaluateLaserEffects(data, fits[1].model, fits[1].calibration);
          const RobustFitBlocks piecewise_blocks = Blocks(at, fits[1].model.FreeColumns());
          const ScoreTester specification(piecewise_blocks, options.hac_lag);
          const ScoreTestResult epsilon = specification.Test(
              SelectColumns(at.jacobian, {kNumLaserParams + kTimeOffsetAsymmetryIndex}));
          consistent =
              specification.ok() && epsilon.identifiable && epsilon.p_value >= options.alpha;
        }
        best = fits[1].cost < fits[0].cost && consistent ? fits[1] : fits[0];
      } else if (!fits.empty()) {
        best = fits[0];
      }
      if (!best) continue;
      f.refitted = true;
      const double kappa = LikelihoodRatioScale(evaluation);
      f.lr_statistic = std::max(0.0, 2.0 * (current.cost - best->cost) / kappa);
      if (c->effect == LaserEffect::kWheelRadiusChange) {
        // The change time was chosen to maximize the fit: the sup distribution.
        f.lr_p_value = SupChiSquareSurvival(f.lr_statistic, f.dof, options.change_trim);
      } else if (c->effect == LaserEffect::kTimeOffset &&
                 best->model.boundary == BoundarySpeedModel::kPiecewiseConstant) {
        // With one-sided speeds the model has a kink at δ = 0 (a |δ| term): the better of two
        // one-sided models, hence twice the χ² tail (Bonferroni).
        f.lr_p_value = std::min(1.0, 2.0 * ChiSquareSurvival(f.lr_statistic, f.dof));
      } else {
        f.lr_p_value = ChiSquareSurvival(f.lr_statistic, f.dof);
      }
      f.delta_aic = f.lr_statistic - 2.0 * f.dof;
      f.delta_bic = f.lr_statistic - f.dof * std::log(3.0 * n);
      // Held-out blocks: the current model and the candidate, each fitted without the block.
      if (!current_held_out) {
        const StatusOr<HeldOut> held = CrossValidate(context, current.model, current.calibration);
        if (!held.ok()) return held.status();
        current_held_out = *held;
      }
      LaserEffectModel cv_model = best->model;
      for (int column : EffectColumns(c->effect)) cv_model.gamma(column - kNumLaserParams) = 0.0;
      const StatusOr<HeldOut> held = CrossValidate(context, cv_model, current.calibration);
      if (!held.ok()) return held.status();
      f.heldout_cost_before = current_held_out->cost;
      f.heldout_cost_after = held->cost;
      f.heldout_rms_before = current_held_out->rms();
      f.heldout_rms_after = held->rms();
      f.heldout_reduction = 1.0 - held->cost / current_held_out->cost;
      const bool confirmed = f.lr_p_value <= f.holm_level && held->cost < current_held_out->cost;
      report("  " + f.name + ": LR " + Format("%.1f", f.lr_statistic) + ", held-out " +
             Format("%+.3f %%", -100.0 * f.heldout_reduction) + (confirmed ? " → adopted" : ""));
      if (!confirmed) {
        c->rejected_on_confirmation = true;
        continue;
      }
      // Adopt.
      const LaserEffectEvaluation after =
          EvaluateLaserEffects(data, best->model, best->calibration, false);
      Adoption adoption;
      adoption.effect = c->effect;
      adoption.shift = current.calibration.ToVector() - best->calibration.ToVector();
      adoption.signal = evaluation.residual - after.residual;
      adoption.contributions = c->test.contributions;
      {
        // The effect's full signal e = r(θ_with, 0) − r(θ_with, γ̂) against the part the fit
        // without it left visible, d = r(θ_without, 0) − r(θ_with, γ̂): share hidden 1 − ‖d‖²/‖e‖².
        LaserEffectModel without = best->model;
        for (int column : EffectColumns(c->effect)) without.gamma(column - kNumLaserParams) = 0.0;
        const LaserEffectEvaluation off =
            EvaluateLaserEffects(data, without, best->calibration, false);
        const double total = (off.residual - after.residual).squaredNorm();
        if (total > 0.0) {
          adoption.absorbed_share =
              std::clamp(1.0 - adoption.signal.squaredNorm() / total, 0.0, 1.0);
        }
      }
      adoptions.push_back(adoption);
      if (c->effect == LaserEffect::kWheelRadiusChange) change_stddev_s = change_sigma;
      current = *best;
      current_held_out = *held;
      f.significant = true;
      c->done = true;
      diagnosis.adopted.push_back(c->effect);
      adopted = true;
      break;
    }
    if (!adopted) break;
  }

  if (std::any_of(current.model.effects.begin(), current.model.effects.end(), UsesBoundarySpeeds)) {
    diagnosis.notes.push_back(
        current.model.boundary == BoundarySpeedModel::kPiecewiseConstant
            ? "boundary speeds: constant within intervals, one-sided at the jumps (it fitted "
              "better than smooth speeds and passed the test of its |δ| term)"
            : "boundary speeds: smooth (instantaneous speeds from the cumulative wheel angles)");
  }
  if (std::any_of(intervals.begin(), intervals.end(),
                  [](const LaserInterval& in) { return in.gap_before; })) {
    diagnosis.notes.push_back(
        "the log has gaps: the time offset and the longitudinal slip assume "
        "the speed continues across them");
  }

  // The final fit and its covariance.
  const LaserEffectEvaluation final_evaluation =
      EvaluateLaserEffects(data, current.model, current.calibration);
  diagnosis.final_fit = MakeReport(context, current, final_evaluation, change_stddev_s);

  // 4. Location and residual structure.
  const std::vector<std::vector<double>> covariates =
      Covariates(context, diagnosis.baseline.estimate);
  const Eigen::MatrixXd before_errors = Unwhitened(data, base_evaluation.residual);
  const Eigen::MatrixXd after_errors = Unwhitened(data, final_evaluation.residual);
  for (size_t c = 0; c < covariates.size(); ++c) {
    diagnosis.covariates.push_back(
        Profile(LaserCovariateNames()[c], CovariateUnits()[c], covariates[c], before_errors,
                base_evaluation.rho1, after_errors, final_evaluation.rho1, options.covariate_bins));
  }
  diagnosis.structure_before = Structure(context, covariates, base_evaluation);
  diagnosis.structure_after = Structure(context, covariates, final_evaluation);

  // The speed-dependent radius's reference speed (for its statement).
  const double typical_speed = data.Contexts(current.model).front().reference_speed;

  // Findings: values from the final fit for adopted effects, else the one-step estimates.
  const LaserParamVector base_sigma = diagnosis.baseline.stddev;
  for (CandidateState& c : candidates) {
    LaserFinding& f = c.finding;
    const LaserEffectInfo& info = EffectInfo(c.effect);
    if (f.significant) {
      f.value = current.model.gamma(info.offset);
      f.stddev = diagnosis.final_fit.gamma_stddev(info.offset);
      for (const Adoption& a : adoptions) {
        if (a.effect != c.effect) continue;
        f.base_shift = a.shift;
        f.absorbed_share = a.absorbed_share;
        for (int i = 0; i < kNumLaserParams; ++i) {
          f.base_shift_sigmas(i) = base_sigma(i) > 0.0 ? a.shift(i) / base_sigma(i) : 0.0;
        }
        // The covariate along which the effect's signal energy ‖d_k‖² varies most (share of
        // its variance explained by binned means), and where its score accrues over time.
        Eigen::VectorXd energy = a.signal.rowwise().squaredNorm();
        energy.array() -= energy.mean();
        double best_explained = -1.0;
        size_t best_covariate = 0;
        for (size_t cov = 0; cov < covariates.size(); ++cov) {
          const BinnedMeans binned = BinByCovariate(
              covariates[cov], energy, Eigen::VectorXd::Ones(n), options.covariate_bins);
          if (binned.explained > best_explained) {
            best_explained = binned.explained;
            best_covariate = cov;
          }
        }
        f.location.covariate = LaserCovariateNames()[best_covariate];
        f.location.explained = std::max(0.0, best_explained);
        if (a.contributions.size() == static_cast<Eigen::Index>(n)) {
          const std::vector<SeriesSegment> segments = SegmentMeans(
              a.contributions, 0.01, 3, options.change_trim, std::max<size_t>(20, n / 50));
          for (const SeriesSegment& s : segments) {
            MismatchLocation::Window w;
            w.start_s = intervals[s.begin].start_s - context.log_start_s;
            w.end_s = intervals[s.end - 1].start_s + intervals[s.end - 1].duration_s -
                      context.log_start_s;
            w.share = s.share;
            w.rate = s.mean(0);
            f.location.windows.push_back(w);
          }
        }
        // Residuals against that covariate, with the component along the signal d_k.
        const double scale = std::sqrt(a.signal.rowwise().squaredNorm().mean());
        Eigen::MatrixXd before(n, 4), after(n, 4);
        before.leftCols(3) = before_errors;
        after.leftCols(3) = after_errors;
        for (size_t k = 0; k < n; ++k) {
          const double norm = scale > 0.0 ? scale : 1.0;
          before(k, 3) = a.signal.row(k).dot(base_evaluation.residual.row(k)) / norm;
          after(k, 3) = a.signal.row(k).dot(final_evaluation.residual.row(k)) / norm;
        }
        f.profile = Profile(f.location.covariate, CovariateUnits()[best_covariate],
                            covariates[best_covariate], before, base_evaluation.rho1, after,
                            final_evaluation.rho1, options.covariate_bins);
      }
      if (c.effect == LaserEffect::kWheelRadiusChange) {
        const double gl = current.model.gamma(info.offset),
                     gr = current.model.gamma(info.offset + 1);
        f.value = diagnosis.final_fit.change_time_s;
        f.stddev = diagnosis.final_fit.change_time_stddev_s;
        f.r_l_after = current.calibration.odometry.left_radius_m * (1.0 + gl);
        f.r_r_after = current.calibration.odometry.right_radius_m * (1.0 + gr);
        // σ by the delta method, ignoring the radius–γ correlation's sign (a bound).
        f.r_l_after_stddev = std::hypot(diagnosis.final_fit.stddev(0) * (1.0 + gl),
                                        current.calibration.odometry.left_radius_m *
                                            diagnosis.final_fit.gamma_stddev(info.offset));
        f.r_r_after_stddev = std::hypot(diagnosis.final_fit.stddev(1) * (1.0 + gr),
                                        current.calibration.odometry.right_radius_m *
                                            diagnosis.final_fit.gamma_stddev(info.offset + 1));
      }
    } else if (!f.confounded && !f.no_information) {
      f.value = f.one_step.size() > 0 ? f.one_step(0) : 0.0;
      f.stddev = f.one_step_stddev.size() > 0 ? f.one_step_stddev(0) : 0.0;
      if (c.effect == LaserEffect::kWheelRadiusChange) {
        f.value = c.change_time_s - context.log_start_s;
        f.stddev = 0.0;
        const LaserCalibration& cal = current.calibration;
        f.r_l_after =
            cal.odometry.left_radius_m * (1.0 + (f.one_step.size() > 0 ? f.one_step(0) : 0.0));
        f.r_r_after =
            cal.odometry.right_radius_m * (1.0 + (f.one_step.size() > 1 ? f.one_step(1) : 0.0));
        f.r_l_after_stddev = cal.odometry.left_radius_m *
                             (f.one_step_stddev.size() > 0 ? f.one_step_stddev(0) : 0.0);
        f.r_r_after_stddev = cal.odometry.right_radius_m *
                             (f.one_step_stddev.size() > 1 ? f.one_step_stddev(1) : 0.0);
      }
    }
    WriteStatement(&f, typical_speed);
  }
  // Adopted findings first, in the order adopted; then by p-value.
  for (LaserEffect effect : diagnosis.adopted) {
    for (const CandidateState& c : candidates) {
      if (c.effect == effect) diagnosis.findings.push_back(c.finding);
    }
  }
  std::vector<const CandidateState*> rest;
  for (const CandidateState& c : candidates) {
    if (!c.finding.significant) rest.push_back(&c);
  }
  std::stable_sort(rest.begin(), rest.end(), [](const CandidateState* a, const CandidateState* b) {
    const auto key = [](const CandidateState* c) {
      return c->finding.confounded || c->finding.no_information ? 2.0 : c->finding.p_value;
    };
    return key(a) < key(b);
  });
  for (const CandidateState* c : rest) diagnosis.findings.push_back(c->finding);
  diagnosis.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return diagnosis;
}

}  // namespace calib
