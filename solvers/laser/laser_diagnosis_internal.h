#ifndef CALIB_SOLVERS_LASER_LASER_DIAGNOSIS_INTERNAL_H_
#define CALIB_SOLVERS_LASER_LASER_DIAGNOSIS_INTERNAL_H_

#include <calib/solvers/diagnosis/finding.h>
#include <calib/solvers/laser/laser_diagnosis.h>
#include <calib/solvers/laser/laser_effect_fit.h>
#include <calib/solvers/stats/score_test.h>
#include <calib/solvers/timing/interval_jitter.h>

#include <Eigen/Core>
#include <limits>
#include <optional>
#include <string>
#include <vector>

// The laser adapter of the diagnosis framework (solvers/diagnosis/), split over
// laser_diagnosis.cc (the forward steps), laser_diagnosis_refit.cc (a candidate's refit and
// confirmation), laser_diagnosis_location.cc (covariates, residual structure, location) and
// laser_diagnosis_words.cc (the laser's words). Not installed for users.
namespace calib::laser_diagnosis {

inline constexpr double kInlierChi2 = 16.27;  // χ²₃ at 99.9 %, as CalibrateLaser.
inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Everything the steps share (all owned by DiagnoseLaser's frame).
struct Context {
  const std::vector<LaserInterval>& intervals;
  const LaserDiagnosisOptions& options;
  LaserEffectData& data;  // Its whitening changes when the timing step models a jitter.
  double log_start_s = 0.0;
  std::vector<std::vector<bool>> train_masks;  // Per held-out block: the training intervals.
  std::vector<std::vector<bool>> test_masks;
};

// One candidate's state across the steps.
struct CandidateState {
  LaserEffect effect;
  LaserFinding finding;
  ScoreTestResult test;
  double change_time_s = kInfinity;  // Located change (on the log clock).
  bool done = false;                 // Adopted or confounded.
};

// What an adopted effect changed (for its finding's shift, location and profile).
struct Adoption {
  LaserEffect effect;
  LaserParamVector shift;
  Eigen::MatrixXd signal;         // Whitened residual change (N × 3) at the adoption.
  Eigen::VectorXd contributions;  // Score contributions over time.
  double absorbed_share = 0.0;    // Of the fitted effect's signal, hidden by the base fit.
};

// The forward search's state.
struct Search {
  LaserEffectFit current;
  std::optional<HeldOutScore> current_held_out;
  std::vector<Adoption> adoptions;
  double change_stddev_s = 0.0;
  double jitter_s = 0.0;  // The modelled stamp jitter (0: none).
  double jitter_stddev_s = 0.0;
};

bool UsesBoundarySpeeds(LaserEffect effect);
std::vector<int> EffectColumns(LaserEffect effect);
// κ of the laser's likelihood-ratio statistics (LikelihoodRatioScale with 3 components).
double LaserLikelihoodRatioScale(const LaserEffectEvaluation& evaluation);
RobustFitBlocks Blocks(const LaserEffectEvaluation& evaluation, const std::vector<int>& columns);

// laser_diagnosis_refit.cc: refits `c` at the current fit; adopts it when the likelihood ratio
// and the held-out blocks confirm it. `evaluation` is the current fit's (with the score tests'
// Jacobians). Returns whether it was adopted.
StatusOr<bool> RefitAndConfirm(const Context& context, const LaserEffectEvaluation& evaluation,
                               CandidateState* c, Search* search);

// laser_diagnosis_timing.cc: the score test of a stamp jitter σ_j at 0 (one-sided) over the
// errors e_k (unwhitened), the time sensitivities and the noise σ_n used to standardise, on the
// inliers.
struct JitterScore {
  double statistic = 0.0;  // z: the slope's t-statistic.
  double p_value = 1.0;
  double slope = 0.0;  // σ_j² in units where the noise scales are 1.
  int boundaries = 0;
};
JitterScore JitterScoreTest(const std::vector<LaserInterval>& intervals,
                            const std::vector<Eigen::Vector3d>& errors,
                            const std::vector<IntervalTimeSensitivity>& g,
                            const Eigen::Vector3d& noise, const std::vector<bool>& inlier,
                            int hac_lag);
// A note when the interval durations cluster at a few values ≥ 5 ms apart (the signature of
// stamps picked up by a clock), "" otherwise.
std::string DurationClusterNote(const std::vector<LaserInterval>& intervals);
// Tests, confirms (profile likelihood ratio and held-out blocks) and, when confirmed, models the
// stamp jitter: context.data is then whitened per interval and search->current refitted.
// Appends its finding to diagnosis->timing_findings.
Status TimingStep(const Context& context, Search* search, LaserDiagnosis* diagnosis);

// A refit's size a wheel does not have (options.plausibility): the reason in words, "" when
// plausible; `follows` gets the covariate its signal follows. `turn_rate` is the log's
// 95th-percentile |ω| (rad/s).
std::string ImplausibleReason(const LaserEffectModel& model, const LaserPlausibility& bounds,
                              LaserEffect effect, double turn_rate, std::string* follows);

// laser_diagnosis_location.cc.
LaserFitReport MakeReport(const Context& context, const LaserEffectFit& fit,
                          const LaserEffectEvaluation& evaluation, double change_stddev_s);
std::vector<std::vector<double>> Covariates(const Context& context,
                                            const LaserCalibration& calibration);
Eigen::MatrixXd Unwhitened(const LaserEffectData& data, const Eigen::MatrixXd& residual);
// The residual structure of the fit at `calibration` (whose covariates it reads).
ResidualStructure StructureAt(const Context& context, const LaserCalibration& calibration,
                              const LaserEffectEvaluation& evaluation);
// The residual structure, the covariate profiles of the baseline and final fits and the location
// of each adopted effect.
void DescribeResiduals(const Context& context, const LaserEffectEvaluation& base_evaluation,
                       const LaserEffectEvaluation& final_evaluation, const Search& search,
                       std::vector<CandidateState>* candidates, LaserDiagnosis* diagnosis);

// laser_diagnosis_words.cc.
std::vector<std::string> ConfoundedWith(const ScoreTestResult& test, const RobustFitBlocks& blocks,
                                        const Eigen::MatrixXd& sensitivity,
                                        const std::vector<std::string>& names);
std::vector<std::string> FreeNames(const LaserEffectModel& model);
std::string LaserStatement(const LaserFinding& finding, double typical_wheel_speed);
const std::vector<std::string>& CovariateUnits();
const std::vector<std::string>& CovariateWords();

}  // namespace calib::laser_diagnosis

#endif  // CALIB_SOLVERS_LASER_LASER_DIAGNOSIS_INTERNAL_H_
