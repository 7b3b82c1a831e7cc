#include <calib/solvers/diagnosis/residual_structure.h>
#include <calib/solvers/laser/laser_diagnosis_internal.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace calib::laser_diagnosis {
namespace {

// A covariate profile of before/after residuals; extra columns beyond the three error
// components (the residual along a signal) are binned but not tested.
CovariateProfile Profile(const std::string& name, const std::string& unit,
                         const std::vector<double>& covariate, const std::vector<size_t>& order,
                         const Eigen::MatrixXd& before, const Eigen::VectorXd& before_weight,
                         const Eigen::MatrixXd& after, const Eigen::VectorXd& after_weight,
                         int bins) {
  CovariateProfile profile;
  profile.name = name;
  profile.unit = unit;
  const BinnedMeans b = BinByCovariate(covariate, order, before, before_weight, bins);
  const BinnedMeans a = BinByCovariate(covariate, order, after, after_weight, bins);
  const BinnedMeans b3 = BinByCovariate(covariate, order, before.leftCols(3), before_weight, bins);
  const BinnedMeans a3 = BinByCovariate(covariate, order, after.leftCols(3), after_weight, bins);
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

// Residual structure of a fit: the covariates' binned means of the whitened residuals and the
// time change point of the weighted whitened residuals.
ResidualStructure Structure(const Context& context,
                            const std::vector<std::vector<double>>& covariates,
                            const std::vector<std::vector<size_t>>& orders,
                            const LaserEffectEvaluation& evaluation) {
  ResidualSeries series;
  series.covariate_names = LaserCovariateNames();
  series.covariates = covariates;
  series.covariate_orders = orders;
  series.values = evaluation.residual;
  series.weights = evaluation.rho1;
  const Eigen::Index n = evaluation.residual.rows();
  series.change_series.resize(n, 3);
  for (Eigen::Index k = 0; k < n; ++k) {
    series.change_series.row(k) = std::sqrt(evaluation.rho1(k)) * evaluation.residual.row(k);
    series.split_time_s.push_back(context.intervals[k].start_s - context.log_start_s);
  }
  StructureWords words;
  words.covariate_words = CovariateWords();
  words.none =
      "No structure is left in the residuals against time, speed, angular rate, v·ω or the "
      "accelerations ";
  words.found = "The residuals still depend on ";
  words.change_format = "their mean changes at t = %.1f s";
  const StructureOptions options{context.options.covariate_bins, context.options.change_trim,
                                 context.options.alpha};
  return TestResidualStructure(series, options, words);
}

std::vector<std::vector<size_t>> Orders(const std::vector<std::vector<double>>& covariates) {
  std::vector<std::vector<size_t>> orders;
  for (const std::vector<double>& covariate : covariates) {
    orders.push_back(CovariateOrder(covariate));
  }
  return orders;
}

// Where an adopted effect lives: the covariate along which its signal energy ‖d_k‖² varies most
// (share of its variance explained by binned means), the time windows where its score accrues,
// and the residuals against that covariate with the component along the signal d_k.
void LocateAdoption(const Context& context, const Adoption& a,
                    const std::vector<std::vector<double>>& covariates,
                    const std::vector<std::vector<size_t>>& orders,
                    const LaserEffectEvaluation& base, const LaserEffectEvaluation& final_fit,
                    LaserFinding* f) {
  const size_t n = context.intervals.size();
  const int bins = context.options.covariate_bins;
  Eigen::VectorXd energy = a.signal.rowwise().squaredNorm();
  energy.array() -= energy.mean();
  double best_explained = -1.0;
  size_t best_covariate = 0;
  for (size_t cov = 0; cov < covariates.size(); ++cov) {
    const BinnedMeans binned =
        BinByCovariate(covariates[cov], orders[cov], energy, Eigen::VectorXd::Ones(n), bins);
    if (binned.explained > best_explained) {
      best_explained = binned.explained;
      best_covariate = cov;
    }
  }
  f->location.covariate = LaserCovariateNames()[best_covariate];
  f->location.explained = std::max(0.0, best_explained);
  if (a.contributions.size() == static_cast<Eigen::Index>(n)) {
    const std::vector<SeriesSegment> segments = SegmentMeans(
        a.contributions, 0.01, 3, context.options.change_trim, std::max<size_t>(20, n / 50));
    for (const SeriesSegment& s : segments) {
      MismatchLocation::Window w;
      const LaserInterval& last = context.intervals[s.end - 1];
      w.start_s = context.intervals[s.begin].start_s - context.log_start_s;
      w.end_s = last.start_s + last.duration_s - context.log_start_s;
      w.share = s.share;
      w.rate = s.mean(0);
      f->location.windows.push_back(w);
    }
  }
  const double scale = std::sqrt(a.signal.rowwise().squaredNorm().mean());
  Eigen::MatrixXd before(n, 4), after(n, 4);
  before.leftCols(3) = Unwhitened(context.data, base.residual);
  after.leftCols(3) = Unwhitened(context.data, final_fit.residual);
  for (size_t k = 0; k < n; ++k) {
    const double norm = scale > 0.0 ? scale : 1.0;
    before(k, 3) = a.signal.row(k).dot(base.residual.row(k)) / norm;
    after(k, 3) = a.signal.row(k).dot(final_fit.residual.row(k)) / norm;
  }
  f->profile =
      Profile(f->location.covariate, CovariateUnits()[best_covariate], covariates[best_covariate],
              orders[best_covariate], before, base.rho1, after, final_fit.rho1, bins);
}

}  // namespace

Eigen::MatrixXd Unwhitened(const LaserEffectData& data, const Eigen::MatrixXd& residual) {
  if (!data.has_interval_sqrt_information()) {
    const Eigen::Matrix3d inverse = data.sqrt_information().inverse();
    return residual * inverse.transpose();
  }
  Eigen::MatrixXd errors(residual.rows(), residual.cols());
  for (Eigen::Index k = 0; k < residual.rows(); ++k) {
    errors.row(k) = (data.sqrt_information(k).inverse() * residual.row(k).transpose()).transpose();
  }
  return errors;
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
      LaserEffectCovariance(evaluation, columns, context.options.hac_lag);
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
  const Eigen::MatrixXd errors = Unwhitened(context.data, evaluation.residual);
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

// The wheel speeds that place interval k among the others: over it and its two neighbours where
// the three follow one another between a log's sample times (raw streams, bags; a tuple file's
// intervals follow one another only as their T are summed). Their errors are then those of the
// wheel angles at the window's ends, not at the interval's own: binned by its own speeds, an
// interval's residual follows the speeds' noise (errors in the regressor), and a long log of
// integer encoder counts had shown a dependence on the angular rate at p < 1e-8 that was the
// counts' rounding alone.
Eigen::Vector2d WindowSpeeds(const std::vector<LaserInterval>& intervals, size_t k,
                             bool sample_times) {
  const LaserInterval& in = intervals[k];
  const Eigen::Vector2d own(in.left_speed, in.right_speed);
  if (!sample_times || k == 0 || k + 1 >= intervals.size()) return own;
  const auto follows = [&](size_t j) {
    const LaserInterval& a = intervals[j - 1];
    const LaserInterval& b = intervals[j];
    return !b.gap_before && std::abs(a.start_s + a.duration_s - b.start_s) < 1e-6 * b.duration_s;
  };
  if (!follows(k) || !follows(k + 1)) return own;
  Eigen::Vector2d angle = Eigen::Vector2d::Zero();
  double duration_s = 0.0;
  for (size_t j = k - 1; j <= k + 1; ++j) {
    angle += intervals[j].duration_s *
             Eigen::Vector2d(intervals[j].left_speed, intervals[j].right_speed);
    duration_s += intervals[j].duration_s;
  }
  return angle / duration_s;
}

std::vector<std::vector<double>> Covariates(const Context& context,
                                            const LaserCalibration& calibration) {
  const std::vector<LaserInterval>& intervals = context.intervals;
  LaserEffectModel smooth;
  smooth.boundary = BoundarySpeedModel::kSmooth;
  const std::vector<LaserEffectContext> contexts = context.data.Contexts(smooth);
  const double rl = calibration.odometry.left_radius_m, rr = calibration.odometry.right_radius_m;
  const double b = calibration.odometry.wheelbase_m;
  const auto v_of = [&](const Eigen::Vector2d& phi) { return 0.5 * (rl * phi(0) + rr * phi(1)); };
  const auto w_of = [&](const Eigen::Vector2d& phi) { return (rr * phi(1) - rl * phi(0)) / b; };
  std::vector<std::vector<double>> covariates(6, std::vector<double>(intervals.size()));
  for (size_t k = 0; k < intervals.size(); ++k) {
    const LaserInterval& in = intervals[k];
    const Eigen::Vector2d phi = WindowSpeeds(intervals, k, context.options.sample_times_estimated);
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

ResidualStructure StructureAt(const Context& context, const LaserCalibration& calibration,
                              const LaserEffectEvaluation& evaluation) {
  const std::vector<std::vector<double>> covariates = Covariates(context, calibration);
  return Structure(context, covariates, Orders(covariates), evaluation);
}

void DescribeResiduals(const Context& context, const LaserEffectEvaluation& base_evaluation,
                       const LaserEffectEvaluation& final_evaluation, const Search& search,
                       std::vector<CandidateState>* candidates, LaserDiagnosis* diagnosis) {
  const std::vector<std::vector<double>> covariates =
      Covariates(context, diagnosis->baseline.estimate);
  // Each covariate sorted once for its profile, the structure tests and the adoptions' places.
  const std::vector<std::vector<size_t>> orders = Orders(covariates);
  const Eigen::MatrixXd before_errors = Unwhitened(context.data, base_evaluation.residual);
  const Eigen::MatrixXd after_errors = Unwhitened(context.data, final_evaluation.residual);
  for (size_t c = 0; c < covariates.size(); ++c) {
    diagnosis->covariates.push_back(Profile(
        LaserCovariateNames()[c], CovariateUnits()[c], covariates[c], orders[c], before_errors,
        base_evaluation.rho1, after_errors, final_evaluation.rho1, context.options.covariate_bins));
  }
  diagnosis->structure_before = Structure(context, covariates, orders, base_evaluation);
  // The same fit (nothing adopted) has the same structure.
  diagnosis->structure_after = &final_evaluation == &base_evaluation
                                   ? diagnosis->structure_before
                                   : Structure(context, covariates, orders, final_evaluation);
  for (CandidateState& c : *candidates) {
    if (!c.finding.significant) continue;
    for (const Adoption& a : search.adoptions) {
      if (a.effect == c.effect) {
        LocateAdoption(context, a, covariates, orders, base_evaluation, final_evaluation,
                       &c.finding);
      }
    }
  }
}

}  // namespace calib::laser_diagnosis
