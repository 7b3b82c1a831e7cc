#include <calib/core/order_statistic.h>
#include <calib/core/se2.h>
#include <calib/core/sin_cos.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/laser/censi_closed_form.h>
#include <calib/solvers/laser/censi_closed_form_internal.h>
#include <calib/solvers/laser/censi_consensus.h>
#include <calib/solvers/laser/laser_motion.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace calib {
namespace censi_internal {

double ScaledConditionNumber(const Eigen::MatrixXd& a) {
  const Eigen::VectorXd d = a.diagonal();
  if ((d.array() <= 0.0).any()) return std::numeric_limits<double>::infinity();
  const Eigen::VectorXd inv_sqrt = d.cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = inv_sqrt.asDiagonal() * a * inv_sqrt.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  const double lo = eig.eigenvalues().minCoeff();
  const double hi = eig.eigenvalues().maxCoeff();
  return lo > 0.0 ? hi / lo : std::numeric_limits<double>::infinity();
}

TranslationRows TranslationEquations(const LaserInterval& interval, double j21, double j22) {
  // The robot displacement per unit wheelbase (b = 1): o = (b·c_x, b·c_y, o_θ), eqs. 12–13 and
  // §II-D, with r_l = −J21, r_r = J22. At constant speed, one sine and cosine of the arc's angle
  // serve the arc and the rows.
  Pose2d c;
  double co, so;
  if (interval.steps.empty()) {
    const double left = interval.left_speed * interval.duration_s;
    const double right = interval.right_speed * interval.duration_s;
    const double distance = (-j21 * left + j22 * right) / 2.0;
    const double angle = j22 * right - (-j21) * left;
    SinCos(angle, &so, &co);
    double s_over, c_over;
    ArcCoefficients(angle, so, co, &s_over, &c_over);
    c = Pose2d(s_over * distance, c_over * distance, angle);
  } else {
    c = IntervalRobotMotion(-j21, j22, 1.0, interval);
    SinCos(c(2), &so, &co);
  }
  const Pose2d& s = interval.sensor_motion;
  TranslationRows l;
  l << -c(0), 1.0 - co, so, s(0), -s(1),  //
      -c(1), -so, 1.0 - co, s(1), s(0);
  return l;
}

StatusOr<Vector5d> SolveTranslation(const Matrix5d& m, const CensiClosedFormOptions& options,
                                    double* lambda) {
  // §II-E: min xᵀMx subject to x4² + x5² = 1. With x = [p; q], the optimal p = −A⁻¹Bq, and q is
  // the unit eigenvector of the Schur complement S = C − BᵀA⁻¹B with the smallest eigenvalue
  // (equivalent to the paper's det(M + λW) = 0 with λ = −eigenvalue, but numerically stable).
  const Eigen::Matrix3d a = m.topLeftCorner<3, 3>();
  const Eigen::Matrix<double, 3, 2> b = m.topRightCorner<3, 2>();
  const Eigen::Matrix2d cc = m.bottomRightCorner<2, 2>();
  const double a_condition = ScaledConditionNumber(a);
  if (!(a_condition < options.max_condition_number * options.max_condition_number)) {
    return Status::NotObservable(
        "the system for b and the sensor position is degenerate (condition number " +
        std::to_string(a_condition) + "): the log needs both arcs (or straight runs) and turns");
  }
  const Eigen::LDLT<Eigen::Matrix3d> a_ldlt(a);
  const Eigen::Matrix2d schur = cc - b.transpose() * a_ldlt.solve(b);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(schur);
  const Eigen::Vector2d q = eig.eigenvectors().col(0);  // Eigenvalues come sorted ascending.
  if (lambda != nullptr) *lambda = -eig.eigenvalues()(0);
  Vector5d x;
  x.head<3>() = -a_ldlt.solve(b * q);
  x.tail<2>() = q;
  if (x(0) < 0.0) x = -x;  // Constraint (19): b > 0.
  if (!(x(0) > 0.0) || !x.allFinite()) {
    return Status::NotObservable(
        "the closed form gave a non-positive wheelbase: the data do not fit a "
        "differential-drive robot");
  }
  return x;
}

}  // namespace censi_internal

namespace {

// The passes run in chunks of at least this many intervals (ParallelSplit: the same sums on any
// number of threads).
constexpr size_t kMinChunk = 500;

// Σ term(interval) over the intervals with use[k] (all when `use` is null), in parallel chunks
// summed on each thread's stack.
template <typename M, typename F>
M SumOverUsed(const std::vector<LaserInterval>& intervals, const std::vector<bool>* use,
              int threads, const F& term) {
  std::vector<M> partial(SplitCount(intervals.size(), kMinChunk), M::Zero());
  ParallelSplit(intervals.size(), threads, kMinChunk, [&](size_t c, size_t begin, size_t end) {
    M sum = M::Zero();
    for (size_t k = begin; k < end; ++k) {
      if (use == nullptr || (*use)[k]) sum += term(intervals[k]);
    }
    partial[c] = sum;
  });
  for (size_t c = 1; c < partial.size(); ++c) partial[0] += partial[c];
  return partial[0];
}

}  // namespace

StatusOr<CensiClosedFormResult> CensiClosedForm(const std::vector<LaserInterval>& intervals,
                                                const std::vector<bool>* use,
                                                const CensiClosedFormOptions& options) {
  const LaserMotionCensus census = CountLaserMotion(intervals, use);
  const std::string missing = DescribeMissingLaserMotion(census);
  if (!missing.empty()) return Status::NotObservable(missing);

  // §II-B: [Δφ_l Δφ_r] [J21 J22]ᵀ = ŝ_θ, by linear least squares: [AᵀA | Aᵀb].
  const Eigen::Matrix<double, 2, 3> normal = SumOverUsed<Eigen::Matrix<double, 2, 3>>(
      intervals, use, options.num_threads, [&](const LaserInterval& interval) {
        const Eigen::Vector2d a = IntervalWheelRotation(interval);
        Eigen::Matrix<double, 2, 3> term;
        term << a * a.transpose(), a * interval.sensor_motion(2);
        return term;
      });
  const Eigen::Matrix2d ata = normal.leftCols<2>();
  const Eigen::Vector2d atb = normal.col(2);
  CensiClosedFormResult result;
  result.samples_used = census.total;
  // Condition number of the stacked system itself is the square root of that of AᵀA.
  result.j_condition_number = std::sqrt(censi_internal::ScaledConditionNumber(ata));
  if (!(result.j_condition_number < options.max_condition_number)) {
    return Status::NotObservable(
        "the rotation system for J21, J22 is degenerate (condition number " +
        std::to_string(result.j_condition_number) +
        "): the log needs turns with different wheel-speed ratios");
  }
  const Eigen::Vector2d j = ata.ldlt().solve(atb);
  result.j21 = j(0);
  result.j22 = j(1);

  // §II-C: eq. 16 stacked into M = Σ L_kᵀ L_k over x = [b, ℓx, ℓy, cos ℓθ, sin ℓθ].
  const censi_internal::Matrix5d m = SumOverUsed<censi_internal::Matrix5d>(
      intervals, use, options.num_threads, [&](const LaserInterval& interval) {
        const censi_internal::TranslationRows l =
            censi_internal::TranslationEquations(interval, result.j21, result.j22);
        return (l.transpose() * l).eval();
      });
  CALIB_ASSIGN_OR_RETURN(const censi_internal::Vector5d x,
                         censi_internal::SolveTranslation(m, options, &result.lambda));
  // r_l = −b·J21 and r_r = +b·J22 (the paper's final formulas print the signs the wrong way).
  result.calibration.odometry = OdometryParams{-x(0) * result.j21, x(0) * result.j22, x(0)};
  result.calibration.base_T_sensor = Pose2d(x(1), x(2), std::atan2(x(4), x(3)));
  if (result.calibration.odometry.left_radius_m <= 0.0 ||
      result.calibration.odometry.right_radius_m <= 0.0) {
    return Status::NotObservable(
        "the closed form gave a non-positive wheel radius (r_l = " +
        std::to_string(result.calibration.odometry.left_radius_m) +
        ", r_r = " + std::to_string(result.calibration.odometry.right_radius_m) +
        "): the wheel readings do not explain the scan rotations with positive radii");
  }
  return result;
}

StatusOr<TrimmedClosedFormResult> CensiClosedFormTrimmed(
    const std::vector<LaserInterval>& intervals, const TrimmedClosedFormOptions& options,
    const ConsensusScreen* given_screen) {
  TrimmedClosedFormResult result;
  result.kept.assign(intervals.size(), true);
  std::optional<CensiClosedFormResult> first;  // The first round's, on the screen's kept set.
  if (options.screen_gross) {
    ConsensusScreenOptions screen_options;
    screen_options.closed_form = options.closed_form;
    ConsensusScreen screen =
        given_screen != nullptr ? *given_screen : ScreenGrossIntervals(intervals, screen_options);
    const StatusOr<CensiClosedFormResult> on_kept =
        ClosedFormOnKept(intervals, screen, options.closed_form);
    // A screen that leaves too little motion for the closed form is not used.
    if (on_kept.ok()) {
      first = *on_kept;
      if (screen.outliers() > 0) {
        result.kept = std::move(screen.kept);
        result.gross = screen.outliers();
        result.first_gross = screen.first_outlier;
      }
    }
  }
  for (int round = 0;; ++round) {
    if (round == 0 && first) {
      result.estimate = *first;
    } else {
      CALIB_ASSIGN_OR_RETURN(result.estimate,
                             CensiClosedForm(intervals, &result.kept, options.closed_form));
    }
    if (round == options.rounds) break;
    // e = ℓ ⊕ ŝ − ô ⊕ ℓ (§III-B), in the robot frame.
    const LaserCalibration& cal = result.estimate.calibration;
    std::vector<double> xy_error(intervals.size()), theta_error(intervals.size());
    ParallelSplit(intervals.size(), options.closed_form.num_threads, kMinChunk,
                  [&](size_t, size_t begin, size_t end) {
                    for (size_t k = begin; k < end; ++k) {
                      const Pose2d o = IntervalRobotMotion(cal.odometry.left_radius_m,
                                                           cal.odometry.right_radius_m,
                                                           cal.odometry.wheelbase_m, intervals[k]);
                      const Pose2d e = Compose(cal.base_T_sensor, intervals[k].sensor_motion) -
                                       Compose(o, cal.base_T_sensor);
                      xy_error[k] = e.head<2>().norm();
                      theta_error[k] = std::abs(WrapAngle(e(2)));
                    }
                  });
    std::vector<double> kept_xy, kept_theta;
    for (size_t k = 0; k < intervals.size(); ++k) {
      if (result.kept[k]) {
        kept_xy.push_back(xy_error[k]);
        kept_theta.push_back(theta_error[k]);
      }
    }
    const auto quantile = [&](std::vector<double> v) {
      const size_t n = static_cast<size_t>(std::floor((1.0 - options.fraction) * (v.size() - 1)));
      return KthSmallest(&v, n);
    };
    const double xy_limit = quantile(kept_xy), theta_limit = quantile(kept_theta);
    for (size_t k = 0; k < intervals.size(); ++k) {
      if (xy_error[k] > xy_limit || theta_error[k] > theta_limit) result.kept[k] = false;
    }
  }
  return result;
}

}  // namespace calib
