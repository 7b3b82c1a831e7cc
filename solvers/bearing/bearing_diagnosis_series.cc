#include <calib/core/text_format.h>
#include <calib/solvers/bearing/bearing_diagnosis_internal.h>
#include <calib/solvers/diagnosis/residual_structure.h>
#include <calib/solvers/diagnosis/statement.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace calib::bearing_diagnosis {
namespace {

constexpr double kDegrees = 180.0 / M_PI;

const std::vector<double>& Covariate(const BearingSeries& s, size_t which) {
  switch (which) {
    case 0:
      return s.t_s;
    case 1:
      return s.speed;
    case 2:
      return s.turn;
    default:
      return s.rate;
  }
}

const char* CovariateUnit(size_t which) {
  static const char* kUnits[] = {"s", "m/s", "rad/s", "rad/s"};
  return kUnits[which];
}

const std::vector<std::string>& CovariateWords() {
  static const std::vector<std::string> words = {"time", "the speed", "the angular rate",
                                                 "the predicted bearing rate"};
  return words;
}

size_t CovariateIndex(const std::string& name) {
  const std::vector<std::string>& names = BearingCovariateNames();
  return std::find(names.begin(), names.end(), name) - names.begin();
}

Eigen::VectorXd Column(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

// Shifts in degrees, 1/m and unitless.
std::vector<ParamWords> BearingParamWords() {
  std::vector<ParamWords> words;
  for (int i = 0; i < kNumBearingParams; ++i) {
    const ParamInfo& info = BearingParamTable()[i];
    const std::string unit = info.display_unit;
    words.push_back({info.name, info.is_angle ? kDegrees : 1.0,
                     info.is_angle ? "°" : (unit.empty() ? "" : " " + unit)});
  }
  return words;
}

}  // namespace

ProblemPtr MakeProblem(const BearingLog& log, const BearingParams& params,
                       const std::vector<std::vector<Pose2d>>& poses, const BearingNoise& noise,
                       BearingAdjustmentOptions adjustment, const Model& model,
                       const std::vector<std::vector<bool>>& use_bearing) {
  adjustment.model_time_offset = model.time_offset;
  adjustment.time_offset_s = model.time_offset_s;
  adjustment.fix_time_offset = model.fix_time_offset;
  adjustment.use_bearing = use_bearing;
  return std::make_unique<BearingProblem>(log, params, poses, noise, adjustment);
}

double LogStart(const BearingLog& log) {
  double start = std::numeric_limits<double>::infinity();
  for (const BearingRun& run : log.runs) {
    if (!run.odometry.empty()) start = std::min(start, run.odometry.front().t_s);
  }
  return std::isfinite(start) ? start : 0.0;
}

BearingSeries Series(const BearingLog& log, const BearingProblem& problem, double log_start_s) {
  BearingSeries series;
  const BearingParams p = problem.params();
  const double r = log.meta.wheel_radius_m;
  const double b = log.meta.wheelbase_m;
  const double delta_b = 1.0 / (b * p.xi_per_m);
  const std::vector<std::vector<double>> errors = problem.BearingErrors();
  std::vector<std::vector<BearingProblem::BearingTermInfo>> terms(log.runs.size());
  for (const auto& info : problem.BearingTerms()) {
    if (terms[info.run].empty()) terms[info.run].resize(log.runs[info.run].bearings.size());
    terms[info.run][info.bearing] = info;
  }
  constexpr double kHalfWindow = 0.1;  // s: speeds from the encoders over t ± this.
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const BearingRun& run = log.runs[i];
    for (size_t j = 0; j < run.bearings.size(); ++j) {
      const double t = run.bearings[j].t_s;
      const Pose2d motion = IntegrateEncoders(run.odometry, t - kHalfWindow, t + kHalfWindow, r, b,
                                              1.0, p.delta, delta_b);
      series.t_s.push_back(t - log_start_s);
      series.speed.push_back(motion(0) / (2.0 * kHalfWindow));
      series.turn.push_back(motion(2) / (2.0 * kHalfWindow));
      const bool has_term = !terms[i].empty() && terms[i][j].run == static_cast<int>(i) &&
                            terms[i][j].bearing == static_cast<int>(j);
      const BearingProblem::BearingTermInfo info =
          has_term ? terms[i][j] : BearingProblem::BearingTermInfo{};
      series.rate.push_back(-info.sensitivity * problem.noise().bearing_sigma_rad);
      series.error.push_back(errors[i][j]);
      series.signal.push_back(has_term ? info.rho1 * info.residual * info.sensitivity : 0.0);
      series.weight.push_back(has_term ? info.rho1 : 0.0);
    }
  }
  return series;
}

CovariateProfile Profile(size_t which, const BearingSeries& before, const BearingSeries& after,
                         int bins, bool with_signal) {
  CovariateProfile profile;
  profile.name = BearingCovariateNames()[which];
  profile.unit = CovariateUnit(which);
  profile.channel_labels = {"bearing error [mrad]"};
  profile.channel_scales = {1e3};
  if (with_signal) {
    profile.channel_labels.push_back("along the effect [σ]");
    profile.channel_scales.push_back(1.0);
  }
  const auto values = [&](const BearingSeries& s) {
    Eigen::MatrixXd v(s.error.size(), with_signal ? 2 : 1);
    v.col(0) = Column(s.error);
    if (with_signal) v.col(1) = Column(s.signal);
    return v;
  };
  // Both fits binned by the baseline's covariate.
  const std::vector<double>& covariate = Covariate(before, which);
  const std::vector<size_t> order = CovariateOrder(covariate);
  const BinnedMeans b =
      BinByCovariate(covariate, order, values(before), Column(before.weight), bins);
  const BinnedMeans a = BinByCovariate(covariate, order, values(after), Column(after.weight), bins);
  profile.center = b.center;
  profile.before_mean = b.mean;
  profile.before_stderr = b.standard_error;
  profile.after_mean = a.mean;
  profile.after_stderr = a.standard_error;
  const BinnedMeans be =
      BinByCovariate(covariate, order, Column(before.error), Column(before.weight), bins);
  const BinnedMeans ae =
      BinByCovariate(covariate, order, Column(after.error), Column(after.weight), bins);
  profile.before_statistic = be.statistic;
  profile.after_statistic = ae.statistic;
  profile.before_p_value = be.p_value;
  profile.after_p_value = ae.p_value;
  profile.dof = be.dof;
  return profile;
}

ResidualStructure Structure(const BearingSeries& s, const BearingDiagnosisOptions& options) {
  ResidualSeries series;
  series.covariate_names = BearingCovariateNames();
  for (size_t c = 0; c < series.covariate_names.size(); ++c) {
    series.covariates.push_back(Covariate(s, c));
  }
  series.values = Column(s.error);
  series.weights = Column(s.weight);
  // The change test on errors in σ units (its CUSUM assumes unit variance per sample).
  double sigma = 0.0;
  for (double e : s.error) sigma += e * e;
  sigma = std::sqrt(sigma / std::max<size_t>(1, s.error.size()));
  if (sigma > 0.0) series.change_series = Column(s.error) / sigma;
  series.split_time_s = s.t_s;
  StructureWords words;
  words.covariate_words = CovariateWords();
  words.none =
      "The bearing residuals follow none of time, speed, angular rate and bearing rate, and "
      "their mean does not change over time ";
  words.found = "The bearing residuals still ";
  words.covariate_prefix = "follow ";
  words.change_format = "change their mean at t = %.0f s";
  return TestResidualStructure(series, {options.covariate_bins, options.change_trim, options.alpha},
                               words);
}

MismatchLocation Locate(const BearingSeries& s, const BearingDiagnosisOptions& options) {
  MismatchLocation location;
  double best = -1.0;
  for (size_t c = 0; c < BearingCovariateNames().size(); ++c) {
    const BinnedMeans b =
        BinByCovariate(Covariate(s, c), Column(s.error), Column(s.weight), options.covariate_bins);
    if (b.explained > best) {
      best = b.explained;
      location.covariate = BearingCovariateNames()[c];
      location.explained = b.explained;
    }
  }
  // Windows: CUSUM segments of the score density (in its own σ units).
  Eigen::VectorXd signal = Column(s.signal);
  const double scale = std::sqrt(signal.squaredNorm() / std::max<Eigen::Index>(1, signal.size()));
  if (scale > 0.0) signal /= scale;
  const double total = signal.sum();
  for (const SeriesSegment& segment : SegmentMeans(signal, options.alpha, 4, options.change_trim,
                                                   std::max<size_t>(10, s.t_s.size() / 20))) {
    MismatchLocation::Window w;
    w.start_s = s.t_s[segment.begin];
    w.end_s = s.t_s[segment.end - 1];
    w.share = total != 0.0
                  ? signal.segment(segment.begin, segment.end - segment.begin).sum() / total
                  : 0.0;
    w.rate = segment.mean(0) * scale;
    location.windows.push_back(w);
  }
  return location;
}

StatusOr<HeldOutScore> CrossValidate(const BearingLog& log, const BearingProblem& start,
                                     const BearingAdjustmentOptions& adjustment, const Model& model,
                                     int folds, const ceres::LossFunction* loss) {
  HeldOutScore out;
  const double sigma = start.noise().bearing_sigma_rad;
  for (int f = 0; f < folds; ++f) {
    std::vector<std::vector<bool>> use(log.runs.size());
    for (size_t i = 0; i < log.runs.size(); ++i) {
      const size_t n = log.runs[i].bearings.size();
      for (size_t j = 0; j < n; ++j) use[i].push_back(static_cast<int>(j * folds / n) != f);
    }
    Model m = model;
    m.time_offset_s = start.time_offset();
    const ProblemPtr problem =
        MakeProblem(log, start.params(), start.poses(), start.noise(), adjustment, m, use);
    CALIB_RETURN_IF_ERROR(problem->Solve());
    const std::vector<std::vector<double>> errors = problem->BearingErrors();
    for (size_t i = 0; i < errors.size(); ++i) {
      for (size_t j = 0; j < errors[i].size(); ++j) {
        if (use[i][j]) continue;
        const double z = errors[i][j] / sigma;
        double rho[3] = {z * z, 1.0, 0.0};
        if (loss != nullptr) loss->Evaluate(z * z, rho);
        out.cost += 0.5 * rho[0];
        if (z * z <= kInlierChi2) {
          out.sum_sq += errors[i][j] * errors[i][j];
          ++out.count;
        }
      }
    }
  }
  return out;
}

std::string BearingStatement(const BearingFinding& f) {
  StatementWords words;
  words.base = "unknowns";
  words.params = BearingParamWords();
  words.confounded =
      "A clock offset of the bearings is exactly absorbed by the runs' start poses "
      "(constant-speed motion only moves each run along its path): this log cannot "
      "see it, so it is not a finding.";
  words.adopted = Format(f.value >= 0.0 ? "The bearings are stamped %.1f ± %.1f ms early "
                                          "relative to the encoders"
                                        : "The bearings are stamped %.1f ± %.1f ms late "
                                          "relative to the encoders",
                         std::abs(f.value) * 1e3, f.stddev * 1e3);
  if (f.one_step_stddev(0) > 0.0) {
    words.estimate = Format("; one-step estimate %.1f ± %.1f ms", f.one_step(0) * 1e3,
                            f.one_step_stddev(0) * 1e3);
  }
  if (!f.location.covariate.empty()) {
    words.covariate = CovariateWords()[CovariateIndex(f.location.covariate)];
  }
  return WriteStatement(f, words);
}

}  // namespace calib::bearing_diagnosis
