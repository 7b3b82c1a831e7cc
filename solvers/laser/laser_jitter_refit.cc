#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/laser/laser_jitter_refit.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace calib {
namespace {

// The rounds end when no log's jitter or noise level moves by this much (relative), or when the
// next round is expected to move no parameter by kSettledStddevs σ: a round moves the parameters
// in proportion to the whitening's change in the round before, so the next movement is this
// round's times the ratio of the two changes.
constexpr double kSettled = 0.01;
constexpr double kSettledStddevs = 0.02;
// Newton steps up to this many σ (see SolveAndCorrect): over a σ or so the robust cost is
// quadratic to a few percent, the next round takes the rest.
constexpr double kNewtonReach = 1.0;

// The jitter each log's whitening uses: its estimate when significant, none otherwise.
double UsedJitter(const IntervalJitterEstimate& estimate) {
  return estimate.significant ? estimate.jitter_s : 0.0;
}

// Relative change of the jitter and the noise levels between two estimates.
double Change(const IntervalJitterEstimate& a, const IntervalJitterEstimate& b) {
  double change =
      ((a.noise_sigma - b.noise_sigma).cwiseQuotient(b.noise_sigma)).cwiseAbs().maxCoeff();
  const double jitter = std::max(UsedJitter(a), UsedJitter(b));
  if (jitter > 0.0) change = std::max(change, std::abs(UsedJitter(a) - UsedJitter(b)) / jitter);
  return change;
}

// Whether the rounds have settled (see kSettled): fed each round's corrected estimate, with the
// parameters' σ, and the change of the jitter and noise levels it led to.
class RoundsSettling {
 public:
  explicit RoundsSettling(const LaserCalibration& start) : previous_(start) {}

  // The estimate's movement in this round (the largest, in σ); none known in the first, whose
  // movement is the jitter's whole effect, no guide to the next round's.
  void Moved(const LaserCalibration& estimate, const LaserParamVector& stddev) {
    if (rounds_++ > 0) {
      movement_ = ((estimate.ToVector() - previous_.ToVector()).cwiseAbs().array() /
                   stddev.array().max(1e-300))
                      .maxCoeff();
    }
    previous_ = estimate;
  }
  bool Settled(double change) const {
    return change < kSettled ||
           (change < previous_change_ && movement_ * change < kSettledStddevs * previous_change_);
  }
  void NextRound(double change) { previous_change_ = change; }

 private:
  LaserCalibration previous_;
  int rounds_ = 0;
  double movement_ = std::numeric_limits<double>::infinity();
  double previous_change_ = 0.0;
};

// Inliers under the per-interval whitening (squared whitened norm below the cut).
std::vector<bool> Inliers(const std::vector<Eigen::Vector3d>& errors,
                          const std::vector<IntervalTimeSensitivity>& sensitivities,
                          const IntervalJitterEstimate& jitter, double inlier_chi2) {
  const std::vector<double> norms =
      JitterWhitenedSquaredNorms(errors, sensitivities, jitter.noise_sigma, UsedJitter(jitter));
  std::vector<bool> inlier(norms.size());
  for (size_t k = 0; k < norms.size(); ++k) inlier[k] = norms[k] < inlier_chi2;
  return inlier;
}

// Moves the problem to the refit's optimum under the current whitening; returns the
// increment-noise correction there as `step` (none without increment covariances). Each round
// starts at an optimum under a whitening that the jitter's estimate has just moved (the base fit's
// first, then the previous round's corrected one), a fraction of σ away on real logs (0.1–0.8σ,
// then 0.02–0.15σ): Newton's step from the correction's own pass gets there (closer than LM, which
// stops a few hundredths of σ short under Tukey's loss), unless it reaches further than
// kNewtonReach σ: then LM solves, and the correction is taken again at its optimum.
StatusOr<LaserProblem::IncrementCorrection> SolveAndCorrect(
    const std::vector<std::vector<Eigen::Matrix2d>>& increment_covariance, LaserProblem* problem,
    LaserCalibrationResult* result) {
  CALIB_ASSIGN_OR_RETURN(LaserProblem::IncrementCorrection near,
                         problem->IncrementNoiseCorrection(increment_covariance));
  const double reach =
      (near.newton_step.array() / near.stddev.array().max(1e-300)).abs().maxCoeff();
  if (reach <= kNewtonReach) {
    ++result->iterations;
    problem->set_calibration(
        LaserCalibration::FromVector(problem->calibration().ToVector() + near.newton_step));
    return near;
  }
  ceres::Solver::Summary summary;
  CALIB_RETURN_IF_ERROR(problem->Solve(&summary));
  result->iterations += static_cast<int>(summary.iterations.size());
  result->converged = Converged(summary);
  return problem->IncrementNoiseCorrection(increment_covariance);
}

}  // namespace

bool EstimateBaseFitJitter(const std::vector<const std::vector<LaserInterval>*>& logs,
                           const LaserCalibrationOptions& options, LaserCalibrationResult* result,
                           const std::vector<std::vector<Eigen::Vector3d>>* errors) {
  bool any = false;
  // A significant jitter is estimated again by the refit, σ of σ_j with it: none here.
  IntervalJitterOptions base = options.jitter;
  base.stddev_wanted = [given = options.jitter.stddev_wanted](const IntervalJitterEstimate& e) {
    return !e.significant && (!given || given(e));
  };
  for (size_t d = 0; d < logs.size(); ++d) {
    const bool given = errors != nullptr && d < errors->size();
    result->interval_jitter.push_back(
        EstimateIntervalJitter(*logs[d], result->estimate, result->noise_sigma[d],
                               result->is_inlier[d], base, given ? &(*errors)[d] : nullptr));
    any = any || result->interval_jitter.back().significant;
  }
  return any;
}

Status RefitWithIntervalJitter(const std::vector<const std::vector<LaserInterval>*>& logs,
                               const LaserCalibrationOptions& options,
                               LaserCalibrationResult* result) {
  std::vector<IntervalJitterEstimate>& jitter = result->interval_jitter;

  // Refit, re-estimate σ_j and the scan noise jointly at the new parameters, refit while they move.
  std::vector<LaserDataset> datasets;
  std::vector<std::vector<IntervalBoundarySpeeds>> speeds(logs.size());
  std::vector<std::vector<IntervalTimeSensitivity>> sensitivities(logs.size());
  for (size_t d = 0; d < logs.size(); ++d) {
    speeds[d] = BoundaryWheelSpeeds(*logs[d]);
    sensitivities[d] = IntervalTimeSensitivities(*logs[d], speeds[d], result->estimate);
    datasets.push_back(LaserDataset{
        logs[d], Eigen::Matrix3d::Identity(),
        JitterSqrtInformation(sensitivities[d], jitter[d].noise_sigma, UsedJitter(jitter[d]))});
  }
  LaserProblem problem(datasets, result->estimate, options.refinement);
  problem.Redescend();  // It starts at the robust estimate: no first, convex stage.
  std::vector<std::vector<bool>> inliers(logs.size());
  const int rounds = std::max(1, options.noise_rounds);
  RoundsSettling settling(result->estimate);
  // The increments' noise also attenuates the radii and wheelbase (errors in the regressors): one
  // corrected-score step removes that bias; σ_j is then re-estimated at the corrected point. The
  // first of several rounds goes without it (its σ_j, 0.04–0.16σ from the corrected point on the
  // real sets, only sets the next round's whitening), which always follows and corrects.
  std::vector<std::vector<Eigen::Matrix2d>> increment_covariance(logs.size());
  for (size_t d = 0; d < logs.size(); ++d) {
    increment_covariance[d] = JitterIncrementCovariances(speeds[d], UsedJitter(jitter[d]));
  }
  for (int round = 0; round < rounds; ++round) {
    const bool corrected = round > 0 || rounds == 1;
    CALIB_ASSIGN_OR_RETURN(const LaserProblem::IncrementCorrection correction,
                           SolveAndCorrect(corrected ? increment_covariance
                                                     : std::vector<std::vector<Eigen::Matrix2d>>{},
                                           &problem, result));
    // The settling compares the optima the whitening moves, without their corrections.
    settling.Moved(problem.calibration(), correction.stddev);
    problem.set_calibration(
        LaserCalibration::FromVector(problem.calibration().ToVector() + correction.step));
    const LaserCalibration estimate = problem.calibration();
    double change = 0.0;
    for (size_t d = 0; d < logs.size(); ++d) {
      sensitivities[d] = IntervalTimeSensitivities(*logs[d], speeds[d], estimate);
      const std::vector<Eigen::Vector3d> errors = problem.Errors(d);
      inliers[d] = Inliers(errors, sensitivities[d], jitter[d], options.inlier_chi2);
      IntervalJitterOptions near = options.jitter;
      near.previous_jitter_s = jitter[d].jitter_s;  // The refit moves σ_j little.
      near.previous_noise_sigma = jitter[d].noise_sigma;
      // σ of σ_j only where this round may be the last (see the loop's end).
      const bool last_round = round + 1 == rounds;
      near.stddev_wanted = [&, last_round](const IntervalJitterEstimate& e) {
        return last_round ||
               (corrected && settling.Settled(std::max(change, Change(e, jitter[d]))));
      };
      IntervalJitterEstimate next =
          EstimateIntervalJitter(errors, sensitivities[d], jitter[d].noise_sigma, inliers[d], near);
      // The decision to model the jitter was taken at the base fit; keep it.
      next.significant = jitter[d].significant;
      change = std::max(change, Change(next, jitter[d]));
      jitter[d] = next;
    }
    if ((corrected && settling.Settled(change)) || round + 1 == rounds) break;
    settling.NextRound(change);
    for (size_t d = 0; d < logs.size(); ++d) {
      increment_covariance[d] = JitterIncrementCovariances(speeds[d], UsedJitter(jitter[d]));
      CALIB_RETURN_IF_ERROR(problem.SetIntervalSqrtInformation(
          d,
          JitterSqrtInformation(sensitivities[d], jitter[d].noise_sigma, UsedJitter(jitter[d]))));
    }
  }

  result->jitter_refit = true;
  result->estimate = problem.calibration();
  result->robust_noise_sigma.clear();  // Of the base fit's estimate.
  result->is_inlier = inliers;
  result->inliers = 0;
  result->noise_sigma.clear();
  std::vector<std::vector<Eigen::Matrix3d>> lag_one(logs.size());
  for (size_t d = 0; d < logs.size(); ++d) {
    result->inliers += static_cast<int>(std::count(inliers[d].begin(), inliers[d].end(), true));
    result->noise_sigma.push_back(jitter[d].noise_sigma);
    lag_one[d] = JitterCrossCovariances(*logs[d], sensitivities[d], UsedJitter(jitter[d]));
  }
  const auto start = std::chrono::steady_clock::now();
  CALIB_ASSIGN_OR_RETURN(const CorrectedCovariance<LaserParamMatrix> covariance,
                         problem.CorrelatedSandwichCovariance(lag_one));
  result->covariance_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result->covariance = covariance.covariance;
  result->covariance_scale = covariance.kappa;
  result->stddev = result->covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  result->observability =
      AnalyzeLaserObservability(result->covariance, result->estimate, result->census);
  for (size_t d = 0; d < logs.size(); ++d) {
    if (!jitter[d].significant) continue;
    result->warnings.push_back(
        (logs.size() > 1 ? "log " + std::to_string(d + 1) + ": " : std::string()) +
        IntervalJitterStatement(jitter[d]));
  }
  return Status::Ok();
}

}  // namespace calib
