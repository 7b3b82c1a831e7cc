#ifndef CALIB_SOLVERS_DIAGNOSIS_STATEMENT_H_
#define CALIB_SOLVERS_DIAGNOSIS_STATEMENT_H_

#include <calib/solvers/diagnosis/finding.h>

#include <Eigen/Core>
#include <string>
#include <vector>

// The one sentence a person reads for each finding. The problem supplies its words (the effect
// with its value, why a confounded effect cannot be seen, the parameters' display units); the
// sentence's structure is the same for every problem.
namespace calib {

// How a base parameter's shift is written: "name +x<suffix> (n σ)", x = shift·scale.
struct ParamWords {
  std::string name;
  double scale = 1.0;
  std::string suffix;  // The unit with its leading space, if any: " mm", "°", " 1/m".
};

struct StatementWords {
  std::string adopted;     // The effect in words with its value ± σ (adopted findings).
  std::string confounded;  // The whole sentence for a confounded finding.
  std::string estimate;    // "; one-step estimate …" for one not adopted ("" for none).
  std::string base;        // What absorbs it: "parameters", "unknowns".
  std::vector<ParamWords> params;
  std::string covariate;  // The words of location.covariate ("" when not located).
};

// shift_i/σ_i, 0 where σ_i is not positive (a fixed or unknown parameter): never inf or NaN.
Eigen::VectorXd ShiftInSigmas(const Eigen::VectorXd& shift, const Eigen::VectorXd& sigma);

// The largest one or two shifts in units of their σ: "r_l +0.123 mm (4.1 σ)".
std::string ShiftWords(const Eigen::VectorXd& shift, const Eigen::VectorXd& sigmas,
                       const std::vector<ParamWords>& params);

// The sentence of `finding`: not excited / confounded / adopted (with the shift the base fit took
// on, the held-out gain and where it lives) / not adopted (with why the refit did not confirm it).
std::string WriteStatement(const Finding& finding, const StatementWords& words);

}  // namespace calib

#endif  // CALIB_SOLVERS_DIAGNOSIS_STATEMENT_H_
