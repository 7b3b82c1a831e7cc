#ifndef CALIB_SOLVERS_LASER_CENSI_CLOSED_FORM_INTERNAL_H_
#define CALIB_SOLVERS_LASER_CENSI_CLOSED_FORM_INTERNAL_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/status.h>
#include <calib/solvers/laser/censi_closed_form.h>

#include <Eigen/Core>

// The two stages of the closed form, shared by the plain estimator and its consensus screen.
namespace calib::censi_internal {

using Vector5d = Eigen::Matrix<double, 5, 1>;
using Matrix5d = Eigen::Matrix<double, 5, 5>;
using TranslationRows = Eigen::Matrix<double, 2, 5>;

// Condition number of a symmetric positive semi-definite matrix after scaling it to unit
// diagonal, so that parameters of different units compare fairly.
double ScaledConditionNumber(const Eigen::MatrixXd& a);

// Eq. 16 of one interval: L_k x = 0 at the truth, x = [b, ℓx, ℓy, cos ℓθ, sin ℓθ]; |L_k x| is
// the interval's translation misfit in metres.
TranslationRows TranslationEquations(const LaserInterval& interval, double j21, double j22);

// §II-E: x minimising xᵀMx with x4² + x5² = 1 and b = x1 > 0; `lambda` (may be null) receives
// the constraint's multiplier. An error when M does not determine b and the sensor position.
StatusOr<Vector5d> SolveTranslation(const Matrix5d& m, const CensiClosedFormOptions& options,
                                    double* lambda);

}  // namespace calib::censi_internal

#endif  // CALIB_SOLVERS_LASER_CENSI_CLOSED_FORM_INTERNAL_H_
