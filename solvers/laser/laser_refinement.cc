#include <calib/core/order_statistic.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/problems/positive_manifold.h>
#include <calib/solvers/common/fused_normal_cost.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/laser/laser_refinement.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <functional>

namespace calib {

namespace {

constexpr char kSingular[] =
    "the information matrix is singular: the log does not determine all six parameters";
constexpr char kTooFew[] = "too few intervals for a covariance";

// The per-interval passes (errors, covariance, the increment-noise correction) run in chunks of at
// least this many intervals (ParallelSplit: the same figures on any number of threads).
constexpr size_t kMinChunk = 500;

}  // namespace

LaserProblem::LaserProblem(const std::vector<LaserDataset>& datasets,
                           const LaserCalibration& initial, const LaserRefinementOptions& options)
    : datasets_(datasets), options_(options) {
  loss_ = std::make_unique<ceres::LossFunctionWrapper>(
      MakeLossFunction(options.loss, options.loss_scale).release(), ceres::TAKE_OWNERSHIP);
  // Without a robust loss the blocks get none: plain least squares, no per-block corrector.
  ceres::LossFunction* block_loss = options.loss == RobustLoss::kNone ? nullptr : loss_.get();
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  // Residual blocks are only added, never removed: skip the bookkeeping that removal needs.
  problem_options.enable_fast_removal = false;
  // Every block is built here with matching sizes: skip Ceres' per-block checks, a noticeable
  // share of the set-up time for a million intervals.
  problem_options.disable_all_safety_checks = true;
  problem_ = std::make_unique<ceres::Problem>(problem_options);
  set_calibration(initial);
  // Radii and wheelbase stay positive through the manifold (the problem owns it).
  problem_->AddParameterBlock(odometry_, 3, new PositiveManifold<3>());
  problem_->AddParameterBlock(base_T_sensor_, 3);
  interval_sqrt_information_.resize(datasets_.size());
  dataset_begin_.push_back(0);
  for (size_t d = 0; d < datasets_.size(); ++d) {
    LaserDataset& dataset = datasets_[d];
    sqrt_information_.push_back(std::make_unique<Eigen::Matrix3d>(dataset.sqrt_information));
    // Moved out of the copy: the problem's own storage, whose addresses the residuals keep.
    if (dataset.interval_sqrt_information.size() == dataset.intervals->size()) {
      interval_sqrt_information_[d] = std::move(dataset.interval_sqrt_information);
    }
    dataset.interval_sqrt_information.clear();
    dataset_begin_.push_back(dataset_begin_.back() + dataset.intervals->size());
  }
  if (options_.per_interval_blocks) {
    AddResidualBlocks(block_loss);
  } else {
    AddFusedBlock(block_loss);
  }
}

void LaserProblem::AddResidualBlocks(ceres::LossFunction* block_loss) {
  for (size_t d = 0; d < datasets_.size(); ++d) {
    for (size_t k = 0; k < datasets_[d].intervals->size(); ++k) {
      problem_->AddResidualBlock(
          LaserResidual::Create((*datasets_[d].intervals)[k], &IntervalSqrtInformation(d, k)),
          block_loss, odometry_, base_T_sensor_);
    }
  }
}

void LaserProblem::AddFusedBlock(ceres::LossFunction* block_loss) {
  using Cost = FusedNormalCost<3, kNumLaserParams>;
  // Per pass: the mounting's sine and cosine; per interval, the rest.
  const auto linearize = [this](const double* const* parameters) {
    return [this, odometry = parameters[0], mounting = SensorMounting(parameters[1])](
               size_t i, Cost::Residual* r, Cost::Jacobian* j) {
      const size_t d = DatasetOf(i);
      const size_t k = i - dataset_begin_[d];
      const LaserInterval& interval = (*datasets_[d].intervals)[k];
      const Eigen::Matrix3d& root = IntervalSqrtInformation(d, k);
      if (j != nullptr) {
        LaserResidual::Linearize(interval, root, odometry, mounting, r, j);
      } else {
        LaserResidual::Evaluate(interval, root, odometry, mounting, r);
      }
      return true;
    };
  };
  auto* cost = NewFusedNormalCost<3, kNumLaserParams>({3, 3}, num_intervals(), linearize,
                                                      block_loss, options_.num_threads, kMinChunk);
  // Evaluate and Linearize give the same residuals (laser_residual.h): a constant-speed interval's
  // from one closed form, a stepped one's to rounding (automatic derivatives divide by a
  // reciprocal), so that Ceres' costs then come from one evaluation of each point.
  cost->set_speculate(true);
  forget_speculation_ = [cost] { cost->ForgetSpeculation(); };
  problem_->AddResidualBlock(cost, nullptr, odometry_, base_T_sensor_);
}

void LaserProblem::Linearize(size_t d, size_t k, const SensorMounting& mounting, Eigen::Vector3d* r,
                             Eigen::Matrix<double, 3, 6>* j) const {
  LaserResidual::Linearize((*datasets_[d].intervals)[k], IntervalSqrtInformation(d, k), odometry_,
                           mounting, r, j);
}

LaserProblem::~LaserProblem() = default;

Status LaserProblem::Solve(
    ceres::Solver::Summary* summary,
    const std::function<void(const ceres::Solver::Summary&)>& after_convex_stage) {
  const auto solve = [&](ceres::Solver::Summary* stage) {
    // The fused block evaluates its intervals on its own threads.
    return calib::Solve(
        LaserRefinementSettings(num_intervals(), options_.max_iterations,
                                options_.per_interval_blocks ? options_.num_threads : 1),
        "the refinement", problem_.get(), stage);
  };
  std::function<void()> redescend;
  if (solves_in_stages()) redescend = [this] { Redescend(); };
  CALIB_RETURN_IF_ERROR(SolveInStages(solve, redescend, summary, after_convex_stage));
  if (!(odometry_[0] > 0.0 && odometry_[1] > 0.0 && odometry_[2] > 0.0)) {
    return Status::NotObservable(
        "the refinement drove a wheel radius or the wheelbase to a non-positive "
        "value: the data do not fit a differential-drive robot");
  }
  return Status::Ok();
}

void LaserProblem::Redescend() {
  if (!redescends() || redescended_) return;
  loss_->Reset(MakeLossFunction(RobustLoss::kTukey, options_.redescending_scale).release(),
               ceres::TAKE_OWNERSHIP);
  redescended_ = true;
  ForgetSpeculation();
}

std::string LaserProblem::LossDescription() const {
  return LossStagesName(options_.loss, redescends() ? options_.redescending_scale : 0.0);
}

LaserCalibration LaserProblem::calibration() const {
  LaserCalibration c;
  c.odometry = OdometryParams{odometry_[0], odometry_[1], odometry_[2]};
  c.base_T_sensor = Pose2d(base_T_sensor_[0], base_T_sensor_[1], WrapAngle(base_T_sensor_[2]));
  return c;
}

void LaserProblem::set_calibration(const LaserCalibration& calibration) {
  odometry_[0] = calibration.odometry.left_radius_m;
  odometry_[1] = calibration.odometry.right_radius_m;
  odometry_[2] = calibration.odometry.wheelbase_m;
  for (int i = 0; i < 3; ++i) base_T_sensor_[i] = calibration.base_T_sensor(i);
}

void LaserProblem::SetSqrtInformation(size_t dataset, const Eigen::Matrix3d& sqrt_information) {
  *sqrt_information_[dataset] = sqrt_information;
  ForgetSpeculation();
}

Status LaserProblem::SetIntervalSqrtInformation(size_t dataset,
                                                const std::vector<Eigen::Matrix3d>& roots) {
  std::vector<Eigen::Matrix3d>& own = interval_sqrt_information_[dataset];
  if (own.empty() || roots.size() != own.size()) {
    return Status::InvalidInput("per-interval whitening: " + std::to_string(roots.size()) +
                                " matrices for a dataset of " + std::to_string(own.size()) +
                                " per-interval ones");
  }
  std::copy(roots.begin(), roots.end(), own.begin());  // In place: the residuals point here.
  ForgetSpeculation();
  return Status::Ok();
}

std::vector<Eigen::Vector3d> LaserProblem::Errors(size_t dataset) const {
  const std::vector<LaserInterval>& intervals = *datasets_[dataset].intervals;
  std::vector<Eigen::Vector3d> errors(intervals.size());
  const SensorMounting mounting(base_T_sensor_);
  ParallelSplit(intervals.size(), options_.num_threads, kMinChunk,
                [&](size_t, size_t begin, size_t end) {
                  for (size_t k = begin; k < end; ++k) {
                    errors[k] = LaserResidual::Error(intervals[k], odometry_, mounting);
                  }
                });
  return errors;
}

LossCorrectionSums LaserProblem::LossSums(size_t dataset,
                                          const std::vector<Eigen::Vector3d>* given) const {
  const std::vector<Eigen::Vector3d> computed =
      given ? std::vector<Eigen::Vector3d>() : Errors(dataset);
  const std::vector<Eigen::Vector3d>& errors = given ? *given : computed;
  std::vector<LossCorrectionSums> partial(SplitCount(errors.size(), kMinChunk));
  ParallelSplit(
      errors.size(), options_.num_threads, kMinChunk, [&](size_t chunk, size_t begin, size_t end) {
        LossCorrectionSums own;  // On the thread's stack (see SandwichCovariance).
        for (size_t k = begin; k < end; ++k) {
          own.Add((IntervalSqrtInformation(dataset, k) * errors[k]).squaredNorm(), loss_.get(), 3);
        }
        partial[chunk] = own;
      });
  LossCorrectionSums sums;
  for (const LossCorrectionSums& own : partial) sums.Add(own);
  return sums;
}

double LaserProblem::LossWeight(double s) const { return EvaluateLoss(loss_.get(), s).rho1; }

StatusOr<CorrectedCovariance<LaserParamMatrix>> LaserProblem::Covariance(
    const std::vector<std::vector<Eigen::Vector3d>>* errors) const {
  ceres::Covariance::Options covariance_options = MakeCovarianceOptions(options_.num_threads);
  // Six parameters: the SVD of the dense 3N × 6 Jacobian is cheaper than a sparse QR.
  covariance_options.algorithm_type = ceres::DENSE_SVD;
  ceres::Covariance covariance(covariance_options);
  const std::vector<const double*> blocks = {odometry_, base_T_sensor_};
  if (!covariance.Compute(blocks, problem_.get())) return Status::NotObservable(kSingular);
  LaserParamMatrix cov;
  if (!covariance.GetCovarianceMatrix(blocks, cov.data())) {
    return Status::Internal("could not read the covariance from Ceres");
  }
  // Ceres fills row-major; the matrix is symmetric, so the layout does not matter.
  LossCorrectionSums sums;
  for (size_t d = 0; d < datasets_.size(); ++d) {
    sums.Add(LossSums(d, errors ? &(*errors)[d] : nullptr));
  }
  const double components = 3.0 * sums.blocks;
  if (components <= kNumLaserParams) return Status::NotObservable(kTooFew);
  CALIB_ASSIGN_OR_RETURN(const double kappa,
                         LossCorrection(sums, components, components - kNumLaserParams));
  return CorrectedCovariance<LaserParamMatrix>{cov * kappa, kappa};
}

StatusOr<CorrectedCovariance<LaserParamMatrix>> LaserProblem::SandwichCovariance() const {
  const int chunks = SplitCount(num_intervals(), kMinChunk);
  std::vector<SandwichSums<kNumLaserParams>> sums(chunks);
  std::atomic<bool> failed{false};
  const SensorMounting mounting(base_T_sensor_);
  ParallelSplit(num_intervals(), options_.num_threads, kMinChunk,
                [&](size_t chunk, size_t begin, size_t end) {
                  Eigen::Matrix<double, 3, kNumLaserParams> j;
                  Eigen::Vector3d r;
                  // Summed on the thread's stack: side by side in `sums` the chunks' sums share
                  // cache lines.
                  SandwichSums<kNumLaserParams> own;
                  for (size_t i = begin; i < end; ++i) {
                    const size_t d = DatasetOf(i);
                    Linearize(d, i - dataset_begin_[d], mounting, &r, &j);
                    if (!r.allFinite() || !j.allFinite()) {
                      failed = true;
                      return;
                    }
                    own.Add(j, r, EvaluateLoss(loss_.get(), r.squaredNorm()));
                  }
                  sums[chunk] = own;
                });
  if (failed) return Status::Internal("a residual could not be evaluated at the estimate");
  for (int c = 1; c < chunks; ++c) sums[0] += sums[c];
  const double n = 3.0 * num_intervals();
  if (n <= kNumLaserParams) return Status::NotObservable(kTooFew);
  StatusOr<CorrectedCovariance<LaserParamMatrix>> sandwich =
      calib::SandwichCovariance(sums[0], n, n - kNumLaserParams);
  if (!sandwich.ok() && sandwich.code() == StatusCode::kNotObservable) {
    return Status::NotObservable(kSingular);
  }
  return sandwich;
}

StatusOr<CorrectedCovariance<LaserParamMatrix>> LaserProblem::CorrelatedSandwichCovariance(
    const std::vector<std::vector<Eigen::Matrix3d>>& lag_one) const {
  const SensorMounting mounting(base_T_sensor_);
  // Interval i's Jacobian and loss weight; false: not evaluable.
  const auto linearize = [&](size_t i, Eigen::Matrix<double, 3, kNumLaserParams>* j,
                             Eigen::Vector3d* r, LossDerivatives* rho) {
    const size_t d = DatasetOf(i);
    Linearize(d, i - dataset_begin_[d], mounting, r, j);
    *rho = EvaluateLoss(loss_.get(), r->squaredNorm());
    return r->allFinite() && j->allFinite();
  };
  std::vector<SandwichSums<kNumLaserParams>> parts(SplitCount(num_intervals(), kMinChunk));
  std::atomic<bool> failed{false};
  ParallelSplit(num_intervals(), options_.num_threads, kMinChunk,
                [&](size_t chunk, size_t begin, size_t end) {
                  SandwichSums<kNumLaserParams> own;  // On the thread's stack.
                  Eigen::Matrix<double, 3, kNumLaserParams> j, j_previous;
                  Eigen::Vector3d r;
                  LossDerivatives rho, rho_previous;
                  // A chunk's first interval pairs with the one before it (evaluated again).
                  if (begin > 0 && !linearize(begin - 1, &j_previous, &r, &rho_previous)) {
                    failed = true;
                    return;
                  }
                  for (size_t i = begin; i < end; ++i) {
                    if (!linearize(i, &j, &r, &rho)) {
                      failed = true;
                      return;
                    }
                    own.Add(j, r, rho);
                    const size_t d = DatasetOf(i);
                    const size_t k = i - dataset_begin_[d];
                    if (k > 0 && d < lag_one.size() && k - 1 < lag_one[d].size()) {
                      // Cov(r_{k−1}, r_k) = L_{k−1}·C·L_kᵀ of the whitened residuals.
                      const Eigen::Matrix3d whitened = IntervalSqrtInformation(d, k - 1) *
                                                       lag_one[d][k - 1] *
                                                       IntervalSqrtInformation(d, k).transpose();
                      const LaserParamMatrix cross =
                          rho_previous.rho1 * rho.rho1 * j_previous.transpose() * whitened * j;
                      own.meat += cross + cross.transpose();
                    }
                    j_previous = j;
                    rho_previous = rho;
                  }
                  parts[chunk] = own;
                });
  if (failed) return Status::Internal("a residual could not be evaluated at the estimate");
  SandwichSums<kNumLaserParams> sums = parts[0];
  for (size_t c = 1; c < parts.size(); ++c) sums += parts[c];
  const double n = 3.0 * num_intervals();
  if (n <= kNumLaserParams) return Status::NotObservable(kTooFew);
  StatusOr<CorrectedCovariance<LaserParamMatrix>> sandwich =
      calib::SandwichCovariance(sums, n, n - kNumLaserParams);
  if (!sandwich.ok() && sandwich.code() == StatusCode::kNotObservable) {
    return Status::NotObservable(kSingular);
  }
  return sandwich;
}

namespace {

// `interval` with `increment` (rad) added to its wheel rotations, spread evenly over its steps,
// into `shifted` (a copy of it: the same steps, whose values are overwritten).
void ShiftIncrements(const LaserInterval& interval, const Eigen::Vector2d& increment,
                     LaserInterval* shifted) {
  shifted->left_speed = interval.left_speed + increment(0) / interval.duration_s;
  shifted->right_speed = interval.right_speed + increment(1) / interval.duration_s;
  for (size_t i = 0; i < interval.steps.size(); ++i) {
    const WheelStep& step = interval.steps[i];
    shifted->steps[i].left_rad =
        step.left_rad + increment(0) * step.duration_s / interval.duration_s;
    shifted->steps[i].right_rad =
        step.right_rad + increment(1) * step.duration_s / interval.duration_s;
  }
}

// ψ = ρ'·Jᵀr of one interval (ρ' given). With r = L·e and J = −L·∂s (LaserResidual), a
// constant-speed interval's is −ρ'·∂sᵀ·(LᵀL)·e: `information` = LᵀL spares the whitening of ∂s.
LaserParamVector Score(const LaserInterval& interval, const Eigen::Matrix3d& root,
                       const Eigen::Matrix3d& information, const double* odometry,
                       const SensorMounting& mounting, double weight) {
  if (interval.steps.empty()) {
    Eigen::Vector3d e;
    Eigen::Matrix<double, 3, kNumLaserParams> ds;
    LaserResidual::ConstantSpeedError(interval, odometry, mounting, &e, &ds);
    return -weight * (ds.transpose() * (information * e));
  }
  Eigen::Matrix<double, 3, kNumLaserParams> j;
  Eigen::Vector3d r;
  LaserResidual::Linearize(interval, root, odometry, mounting, &r, &j);
  return weight * j.transpose() * r;
}

}  // namespace

void LaserProblem::AddIncrementCorrection(size_t d, size_t k, const Eigen::Matrix2d* covariance,
                                          const SensorMounting& mounting,
                                          IncrementSums* sums) const {
  const LaserInterval& interval = (*datasets_[d].intervals)[k];
  const Eigen::Matrix3d& root = IntervalSqrtInformation(d, k);
  Eigen::Matrix<double, 3, kNumLaserParams> j;
  Eigen::Vector3d r;
  LaserResidual::Linearize(interval, root, odometry_, mounting, &r, &j);
  const LossDerivatives rho = EvaluateLoss(loss_.get(), r.squaredNorm());
  const double weight = rho.rho1;
  const LaserParamVector g = j.transpose() * r;
  const LaserParamVector center = weight * g;
  sums->gradient += center;
  // The upper triangles only, in loops the compiler unrolls (as FusedNormalCost does); mirrored
  // once after the pass.
  const Eigen::Matrix<double, 3, kNumLaserParams> weighted = weight * j;
  const double curvature = 2.0 * rho.rho2;
  for (int b = 0; b < kNumLaserParams; ++b) {
    for (int a = 0; a <= b; ++a) {
      sums->hessian(a, b) += weighted.col(a).dot(j.col(b));
      sums->curvature(a, b) += curvature * g(a) * g(b);
    }
  }
  if (covariance == nullptr) return;
  // 2×2: the closed-form eigen decomposition (the iterative one cost as much as a residual).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen;
  eigen.computeDirect(*covariance);
  LaserInterval shifted = interval;  // One copy for the four evaluations.
  const Eigen::Matrix3d information = root.transpose() * root;
  for (int i = 0; i < 2; ++i) {
    const double variance = eigen.eigenvalues()(i);
    if (!(variance > 0.0)) continue;
    const Eigen::Vector2d u = std::sqrt(variance) * eigen.eigenvectors().col(i);
    ShiftIncrements(interval, u, &shifted);
    const LaserParamVector plus = Score(shifted, root, information, odometry_, mounting, weight);
    ShiftIncrements(interval, -u, &shifted);
    sums->correction +=
        0.5 *
        (plus + Score(shifted, root, information, odometry_, mounting, weight) - 2.0 * center);
  }
}

StatusOr<LaserProblem::IncrementCorrection> LaserProblem::IncrementNoiseCorrection(
    const std::vector<std::vector<Eigen::Matrix2d>>& increment_covariance) const {
  const SensorMounting mounting(base_T_sensor_);
  std::vector<IncrementSums> sums(SplitCount(num_intervals(), kMinChunk));
  ParallelSplit(num_intervals(), options_.num_threads, kMinChunk,
                [&](size_t chunk, size_t begin, size_t end) {
                  IncrementSums own;  // On the thread's stack (see SandwichCovariance).
                  for (size_t i = begin; i < end; ++i) {
                    const size_t d = DatasetOf(i), k = i - dataset_begin_[d];
                    const bool given =
                        d < increment_covariance.size() && k < increment_covariance[d].size();
                    AddIncrementCorrection(d, k, given ? &increment_covariance[d][k] : nullptr,
                                           mounting, &own);
                  }
                  sums[chunk] = own;
                });
  for (size_t c = 1; c < sums.size(); ++c) {
    sums[0].hessian += sums[c].hessian;
    sums[0].curvature += sums[c].curvature;
    sums[0].gradient += sums[c].gradient;
    sums[0].correction += sums[c].correction;
  }
  const LaserParamMatrix hessian = sums[0].hessian.selfadjointView<Eigen::Upper>();
  const LaserParamMatrix newton_hessian =
      hessian + LaserParamMatrix(sums[0].curvature.selfadjointView<Eigen::Upper>());
  const Eigen::LDLT<LaserParamMatrix> ldlt(hessian);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
    return Status::NotObservable(kSingular);
  }
  const LaserParamMatrix inverse = ldlt.solve(LaserParamMatrix::Identity());
  IncrementCorrection out{ldlt.solve(sums[0].correction),
                          inverse.diagonal().cwiseMax(0.0).cwiseSqrt(),
                          -ldlt.solve(sums[0].gradient)};
  // Newton's step where the score's derivative is positive definite (near the optimum), else the
  // Gauss–Newton one.
  const Eigen::LDLT<LaserParamMatrix> newton(newton_hessian);
  if (newton.info() == Eigen::Success && (newton.vectorD().array() > 0.0).all()) {
    out.newton_step = -newton.solve(sums[0].gradient);
  }
  return out;
}

Eigen::Vector3d RobustNoiseSigma(const std::vector<Eigen::Vector3d>& errors, int num_threads) {
  Eigen::Vector3d sigma = Eigen::Vector3d::Zero();
  if (errors.empty()) return Eigen::Vector3d::Ones();
  // The components side by side: each is two selections over every error.
  ParallelSplit(3, num_threads, 1, [&](size_t, size_t begin, size_t end) {
    std::vector<double> values(errors.size());
    for (size_t j = begin; j < end; ++j) {
      for (size_t k = 0; k < errors.size(); ++k) values[k] = errors[k](j);
      const double median = UpperMedian(&values);
      for (double& v : values) v = std::abs(v - median);
      // Floor: 1e-12 m or rad keeps noise-free data well-posed without affecting real data.
      sigma(j) = std::max(1.4826 * UpperMedian(&values), 1e-12);
    }
  });
  return sigma;
}

}  // namespace calib
