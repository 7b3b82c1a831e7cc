#include <calib/solvers/diagnosis/confirmation.h>
#include <calib/solvers/laser/laser_diagnosis_internal.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

namespace calib::laser_diagnosis {
namespace {

// Fits `model` on each training set and evaluates it on the held-out block.
StatusOr<HeldOutScore> CrossValidate(const Context& context, const LaserEffectModel& model,
                                     const LaserCalibration& initial) {
  HeldOutScore held_out;
  held_out.components = 3;
  for (size_t f = 0; f < context.train_masks.size(); ++f) {
    CALIB_ASSIGN_OR_RETURN(const LaserEffectFit fit,
                           FitLaserEffects(context.data, model, initial, &context.train_masks[f]));
    const LaserEffectEvaluation evaluation =
        EvaluateLaserEffects(context.data, fit.model, fit.calibration, false);
    held_out.cost += evaluation.Cost(&context.test_masks[f]);
    for (Eigen::Index k = 0; k < evaluation.residual.rows(); ++k) {
      if (!context.test_masks[f][k]) continue;
      const double s = evaluation.residual.row(k).squaredNorm();
      if (s < kInlierChi2) {
        held_out.sum_sq += s;
        ++held_out.count;
      }
    }
  }
  return held_out;
}

// The change time's profile likelihood: the cost of refits with the change at given times.
class ChangeProfile {
 public:
  ChangeProfile(const LaserEffectData& data, const LaserEffectFit& fit)
      : data_(data), start_(fit), best_(fit) {
    cost_[fit.model.change_time_s] = fit.cost;
  }
  void Try(double t) {
    if (cost_.count(t)) return;
    LaserEffectModel model = start_.model;
    model.change_time_s = t;
    const StatusOr<LaserEffectFit> fit = FitLaserEffects(data_, model, start_.calibration);
    if (!fit.ok()) return;
    cost_[t] = fit->cost;
    if (fit->cost < best_.cost) best_ = *fit;
  }
  const LaserEffectFit& best() const { return best_; }
  const std::map<double, double>& cost() const { return cost_; }

 private:
  const LaserEffectData& data_;
  const LaserEffectFit start_;
  LaserEffectFit best_;
  std::map<double, double> cost_;  // Change time → cost.
};

// The half-width of the 68.3 % set of the profile: every profiled time whose drop is ≤ 3.5 (the
// profile is a random walk, the set need not be connected); its hull, each end interpolated to
// the next time outside.
double ProfileHalfWidth(const ChangeProfile& profile, double kappa) {
  constexpr double kDrop68 = 3.50;  // (1 − e^{−q/2})² = 0.683.
  const double best_cost = profile.best().cost;
  const auto drop = [&](double cost) { return 2.0 * (cost - best_cost) / kappa; };
  std::vector<std::pair<double, double>> points(profile.cost().begin(), profile.cost().end());
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
  return 0.5 * (right - left);
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
ChangeLocation LocateChange(const Context& context, const LaserEffectFit& fit) {
  constexpr int kCoarse = 24;
  constexpr int kBoundaryWindow = 6;
  constexpr double kStddevPerQuantile = 1.75;  // √26 / 2.9.
  const std::vector<LaserInterval>& intervals = context.intervals;
  const size_t n = intervals.size();
  ChangeProfile profile(context.data, fit);
  const auto index_of = [&](double t) {
    size_t index = 0;
    while (index + 1 < n && intervals[index].start_s < t) ++index;
    return index;
  };
  const auto around = [&](size_t index) {
    for (size_t j = index > kBoundaryWindow ? index - kBoundaryWindow : 1;
         j <= std::min(n - 1, index + kBoundaryWindow); ++j) {
      profile.Try(intervals[j].start_s);
    }
  };
  const double trim = std::clamp(context.options.change_trim, 0.0, 0.49);
  const size_t lo = std::max<size_t>(1, static_cast<size_t>(std::ceil(trim * n)));
  const size_t hi = std::min(n - 1, static_cast<size_t>(std::floor((1.0 - trim) * n)));
  for (int g = 0; g <= kCoarse && hi > lo; ++g) {
    profile.Try(intervals[lo + (hi - lo) * g / kCoarse].start_s);
  }
  around(index_of(fit.model.change_time_s));
  around(index_of(profile.best().model.change_time_s));  // The best boundary's neighbours.
  const size_t best_index = index_of(profile.best().model.change_time_s);
  const int steps = std::max(1, context.options.change_profile_steps);
  const double boundary = intervals[best_index].start_s;
  for (int s = -steps + 1; s < steps; ++s) {
    const LaserInterval& in =
        s < 0 && best_index > 0 ? intervals[best_index - 1] : intervals[best_index];
    profile.Try(boundary + in.duration_s * s / steps);
  }
  const LaserEffectFit& best = profile.best();
  const double kappa = LaserLikelihoodRatioScale(
      EvaluateLaserEffects(context.data, best.model, best.calibration, false));
  const double grid = intervals[best_index].duration_s / steps;
  return {best,
          std::max(kStddevPerQuantile * ProfileHalfWidth(profile, kappa), grid / std::sqrt(12.0))};
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

// The model without `effect`'s values (γ = 0; still modelled).
LaserEffectModel WithoutValues(LaserEffectModel model, LaserEffect effect) {
  for (int column : EffectColumns(effect)) model.gamma(column - kNumLaserParams) = 0.0;
  return model;
}

// The piecewise model's one-sided speeds add a |δ|·h term at speed jumps, which can fit other
// mismatches there. It is preferred when it fits better and passes a score test of ε = 0 (the
// coefficient of h equal to |δ|, not freely chosen).
bool PiecewiseIsConsistent(const Context& context, const LaserEffectFit& piecewise) {
  if (!piecewise.model.Has(LaserEffect::kTimeOffset)) return true;
  const LaserEffectEvaluation at =
      EvaluateLaserEffects(context.data, piecewise.model, piecewise.calibration);
  const ScoreTester specification(Blocks(at, piecewise.model.FreeColumns()),
                                  context.options.hac_lag);
  const ScoreTestResult epsilon =
      specification.Test(SelectColumns(at.jacobian, {kNumLaserParams + kTimeOffsetAsymmetryIndex}));
  return specification.ok() && epsilon.identifiable && epsilon.p_value >= context.options.alpha;
}

// The refit with the candidate (both boundary models when it uses them and none is fixed), and
// the change time's standard deviation for a radius change.
std::optional<LaserEffectFit> Refit(const Context& context, const CandidateState& c,
                                    const LaserEffectFit& current, double* change_sigma) {
  std::vector<BoundarySpeedModel> boundaries = {current.model.boundary};
  if (context.options.boundary == BoundaryChoice::kAuto && UsesBoundarySpeeds(c.effect)) {
    boundaries = {BoundarySpeedModel::kSmooth, BoundarySpeedModel::kPiecewiseConstant};
  }
  std::vector<LaserEffectFit> fits;
  for (BoundarySpeedModel boundary : boundaries) {
    // From γ = 0: the one-step value can be far off where the model is far from linear.
    LaserEffectModel next =
        WithEffect(current.model, c.effect, Eigen::VectorXd::Zero(c.test.dof), c.change_time_s);
    next.boundary = boundary;
    StatusOr<LaserEffectFit> fit = FitLaserEffects(context.data, next, current.calibration);
    if (!fit.ok()) continue;
    if (c.effect == LaserEffect::kWheelRadiusChange) {
      const ChangeLocation located = LocateChange(context, *fit);
      *fit = located.fit;
      *change_sigma = located.stddev_s;
    }
    fits.push_back(*fit);
  }
  if (fits.size() == 2) {
    return fits[1].cost < fits[0].cost && PiecewiseIsConsistent(context, fits[1]) ? fits[1]
                                                                                  : fits[0];
  }
  if (fits.empty()) return std::nullopt;
  return fits[0];
}

// The null law of the likelihood ratio of `effect` in `model`.
double LikelihoodRatioSurvival(LaserEffect effect, const LaserEffectModel& model, int dof,
                               double change_trim, double statistic) {
  if (effect == LaserEffect::kWheelRadiusChange) {
    // The change time was chosen to maximize the fit: the sup distribution.
    return SupChiSquareSurvival(statistic, dof, change_trim);
  }
  if (effect == LaserEffect::kTimeOffset &&
      model.boundary == BoundarySpeedModel::kPiecewiseConstant) {
    // With one-sided speeds the model has a kink at δ = 0 (a |δ| term): the better of two
    // one-sided models, hence twice the χ² tail (Bonferroni).
    return std::min(1.0, 2.0 * ChiSquareSurvival(statistic, dof));
  }
  return ChiSquareSurvival(statistic, dof);
}

// What adopting `best` changes: the shift of the base parameters, the residual change and the
// share of the effect's signal that the fit without it had hidden.
Adoption Adopt(const Context& context, const LaserEffectEvaluation& evaluation,
               const CandidateState& c, const LaserEffectFit& current, const LaserEffectFit& best) {
  const LaserEffectEvaluation after =
      EvaluateLaserEffects(context.data, best.model, best.calibration, false);
  Adoption adoption;
  adoption.effect = c.effect;
  adoption.shift = current.calibration.ToVector() - best.calibration.ToVector();
  adoption.signal = evaluation.residual - after.residual;
  adoption.contributions = c.test.contributions;
  // The effect's full signal e = r(θ_with, 0) − r(θ_with, γ̂) against the part the fit
  // without it left visible, d = r(θ_without, 0) − r(θ_with, γ̂): share hidden 1 − ‖d‖²/‖e‖².
  const LaserEffectEvaluation off = EvaluateLaserEffects(
      context.data, WithoutValues(best.model, c.effect), best.calibration, false);
  const double total = (off.residual - after.residual).squaredNorm();
  if (total > 0.0) {
    adoption.absorbed_share = std::clamp(1.0 - adoption.signal.squaredNorm() / total, 0.0, 1.0);
  }
  return adoption;
}

// The 95th percentile of |ω| over the intervals (rad/s).
double TurnRate95(const Context& context, const LaserCalibration& calibration) {
  const OdometryParams& p = calibration.odometry;
  std::vector<double> rates;
  for (const LaserInterval& in : context.intervals) {
    rates.push_back(std::abs(p.right_radius_m * in.right_speed - p.left_radius_m * in.left_speed) /
                    p.wheelbase_m);
  }
  const size_t i = rates.size() * 95 / 100;
  std::nth_element(rates.begin(), rates.begin() + i, rates.end());
  return rates[i];
}

}  // namespace

StatusOr<bool> RefitAndConfirm(const Context& context, const LaserEffectEvaluation& evaluation,
                               CandidateState* c, Search* search) {
  LaserFinding& f = c->finding;
  double change_sigma = 0.0;
  const std::optional<LaserEffectFit> best = Refit(context, *c, search->current, &change_sigma);
  if (!best) return false;
  const double n = static_cast<double>(context.intervals.size());
  const LikelihoodRatio lr =
      TestLikelihoodRatio(search->current.cost, best->cost, LaserLikelihoodRatioScale(evaluation),
                          f.dof, std::log(3.0 * n), [&](double statistic) {
                            return LikelihoodRatioSurvival(c->effect, best->model, f.dof,
                                                           context.options.change_trim, statistic);
                          });
  // Held-out blocks: the current model and the candidate, each fitted without the block.
  if (!search->current_held_out) {
    CALIB_ASSIGN_OR_RETURN(search->current_held_out, CrossValidate(context, search->current.model,
                                                                   search->current.calibration));
  }
  CALIB_ASSIGN_OR_RETURN(
      const HeldOutScore held,
      CrossValidate(context, WithoutValues(best->model, c->effect), search->current.calibration));
  const bool confirmed = Confirm(lr, *search->current_held_out, held, &f);
  if (context.options.progress) context.options.progress(ConfirmationProgress(f, confirmed));
  if (!confirmed) return false;
  // Confirmed, but of a size the physics does not have: a structure in the residuals, not
  // adopted as that effect (its refit value is kept for the report).
  f.implausible_reason = ImplausibleReason(best->model, context.options.plausibility, c->effect,
                                           TurnRate95(context, best->calibration), &f.follows);
  f.implausible = !f.implausible_reason.empty();
  if (f.implausible) {
    const LaserEffectInfo& info = EffectInfo(c->effect);
    f.value = best->model.gamma(info.offset);
    if (context.options.progress) context.options.progress("  → implausible size: " + f.name);
    return false;
  }
  search->adoptions.push_back(Adopt(context, evaluation, *c, search->current, *best));
  if (c->effect == LaserEffect::kWheelRadiusChange) search->change_stddev_s = change_sigma;
  search->current = *best;
  search->current_held_out = held;
  f.significant = true;
  c->done = true;
  return true;
}

}  // namespace calib::laser_diagnosis
