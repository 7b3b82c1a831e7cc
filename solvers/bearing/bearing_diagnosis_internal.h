#ifndef CALIB_SOLVERS_BEARING_BEARING_DIAGNOSIS_INTERNAL_H_
#define CALIB_SOLVERS_BEARING_BEARING_DIAGNOSIS_INTERNAL_H_

#include <calib/solvers/bearing/bearing_diagnosis.h>
#include <ceres/loss_function.h>

#include <memory>
#include <string>
#include <vector>

// The bearing adapter of the diagnosis framework (solvers/diagnosis/), split over
// bearing_diagnosis.cc (the steps) and bearing_diagnosis_series.cc (per-bearing series,
// residual structure, location, held-out blocks and words). Not part of the API.
namespace calib::bearing_diagnosis {

inline constexpr double kInlierChi2 = 10.83;  // χ²₁ at 99.9 %, as CalibrateBearing.

using ProblemPtr = std::unique_ptr<BearingProblem>;

struct Model {
  bool time_offset = false;
  double time_offset_s = 0.0;
  bool fix_time_offset = false;
};

ProblemPtr MakeProblem(const BearingLog& log, const BearingParams& params,
                       const std::vector<std::vector<Pose2d>>& poses, const BearingNoise& noise,
                       BearingAdjustmentOptions adjustment, const Model& model,
                       const std::vector<std::vector<bool>>& use_bearing = {});

// Per bearing (in log order, runs concatenated): what the location and the plots need.
struct BearingSeries {
  std::vector<double> t_s;     // From the log start.
  std::vector<double> speed;   // v (m/s, nominal wheel radius, gauge δR = 1).
  std::vector<double> turn;    // ω (rad/s).
  std::vector<double> rate;    // Predicted bearing rate (rad/s).
  std::vector<double> error;   // wrap(β − β̂) (rad).
  std::vector<double> signal;  // ρ'·r·∂r/∂τ (score density; 0 for left-out bearings).
  std::vector<double> weight;  // ρ'.
};

double LogStart(const BearingLog& log);
// `problem` models τ (the sensitivity is that of τ at its current value).
BearingSeries Series(const BearingLog& log, const BearingProblem& problem, double log_start_s);
CovariateProfile Profile(size_t which, const BearingSeries& before, const BearingSeries& after,
                         int bins, bool with_signal);
ResidualStructure Structure(const BearingSeries& s, const BearingDiagnosisOptions& options);
MismatchLocation Locate(const BearingSeries& s, const BearingDiagnosisOptions& options);

// The held-out cost ½Σρ and inlier RMS of the bearings left out of a fit, summed over the folds
// (every run cut into `folds` contiguous blocks; fold f leaves block f of every run out).
StatusOr<HeldOutScore> CrossValidate(const BearingLog& log, const BearingProblem& start,
                                     const BearingAdjustmentOptions& adjustment, const Model& model,
                                     int folds, const ceres::LossFunction* loss);

std::string BearingStatement(const BearingFinding& finding);

}  // namespace calib::bearing_diagnosis

#endif  // CALIB_SOLVERS_BEARING_BEARING_DIAGNOSIS_INTERNAL_H_
