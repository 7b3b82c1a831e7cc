#include <calib/solvers/laser/laser_refinement.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

#include <calib/problems/laser/laser_residual.h>
#include <calib/problems/positive_manifold.h>

namespace calib {

namespace {

// Runs body(chunk, begin, end) over [0, n) split into `threads` contiguous chunks, in parallel:
// the per-interval passes (errors, covariance) are a noticeable share of a million-interval run.
template <typename Body>
void ParallelChunks(size_t n, int threads, const Body& body) {
  const size_t chunks = std::max<size_t>(1, std::min<size_t>(threads, n / 10000 + 1));
  std::vector<std::thread> workers;
  for (size_t c = 1; c < chunks; ++c) {
    workers.emplace_back([&, c]() { body(c, n * c / chunks, n * (c + 1) / chunks); });
  }
  body(0, 0, n / chunks);
  for (std::thread& worker : workers) worker.join();
}

}  // namespace

LaserProblem::LaserProblem(const std::vector<LaserDataset>& datasets,
                           const LaserCalibration& initial, const LaserRefinementOptions& options)
    : datasets_(datasets), options_(options) {
  loss_ = MakeLossFunction(options.loss, options.loss_scale);
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
  for (const LaserDataset& dataset : datasets_) {
    sqrt_information_.push_back(std::make_unique<Eigen::Matrix3d>(dataset.sqrt_information));
    for (const LaserInterval& interval : *dataset.intervals) {
      ceres::CostFunction* cost = LaserResidual::Create(interval, sqrt_information_.back().get());
      problem_->AddResidualBlock(cost, loss_.get(), odometry_, base_T_sensor_);
      cost_functions_.push_back(cost);
      cost_dataset_.push_back(sqrt_information_.size() - 1);
    }
  }
}

LaserProblem::~LaserProblem() = default;

Status LaserProblem::Solve(ceres::Solver::Summary* summary) {
  ceres::Solver::Options solver_options;
  solver_options.minimizer_type = ceres::TRUST_REGION;
  solver_options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options_.max_iterations;
  solver_options.num_threads = options_.num_threads;
  // Stop once an iteration lowers the cost by less than ~0.01 (in units of whitened χ²/2): the
  // step then moved the estimate by about a tenth of its sigma, and what remains is smaller
  // still. The cost is about 1.5 per interval, hence the relative tolerance.
  solver_options.function_tolerance =
      std::min(1e-6, 0.005 / std::max<size_t>(1, cost_functions_.size()));
  solver_options.gradient_tolerance = 1e-12;
  solver_options.parameter_tolerance = 1e-10;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary local_summary;
  ceres::Solve(solver_options, problem_.get(), &local_summary);
  if (summary != nullptr) *summary = local_summary;
  if (local_summary.termination_type == ceres::FAILURE ||
      !std::isfinite(local_summary.final_cost)) {
    return Status::Error("the refinement failed: " + local_summary.message);
  }
  if (!(odometry_[0] > 0.0 && odometry_[1] > 0.0 && odometry_[2] > 0.0)) {
    return Status::Error(
        "the refinement drove a wheel radius or the wheelbase to a non-positive "
        "value: the data do not fit a differential-drive robot");
  }
  return Status::Ok();
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
}

std::vector<Eigen::Vector3d> LaserProblem::Errors(size_t dataset) const {
  const std::vector<LaserInterval>& intervals = *datasets_[dataset].intervals;
  std::vector<Eigen::Vector3d> errors(intervals.size());
  ParallelChunks(intervals.size(), options_.num_threads, [&](size_t, size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      errors[k] = LaserResidual::Error(intervals[k], odometry_, base_T_sensor_);
    }
  });
  return errors;
}

std::vector<double> LaserProblem::WhitenedSquaredNorms(size_t dataset) const {
  std::vector<double> s;
  const Eigen::Matrix3d& l = *sqrt_information_[dataset];
  for (const Eigen::Vector3d& e : Errors(dataset)) s.push_back((l * e).squaredNorm());
  return s;
}

double LaserProblem::LossWeight(double s) const {
  if (!loss_) return 1.0;
  double rho[3];
  loss_->Evaluate(s, rho);
  return rho[1];
}

StatusOr<LaserParamMatrix> LaserProblem::Covariance() const {
  ceres::Covariance::Options covariance_options;
  covariance_options.num_threads = options_.num_threads;
  covariance_options.algorithm_type = ceres::SPARSE_QR;
  covariance_options.apply_loss_function = true;
  ceres::Covariance covariance(covariance_options);
  const std::vector<const double*> blocks = {odometry_, base_T_sensor_};
  if (!covariance.Compute(blocks, problem_.get())) {
    return Status::Error(
        "the information matrix is singular: the log does not determine all six "
        "parameters");
  }
  LaserParamMatrix cov;
  if (!covariance.GetCovarianceMatrix(blocks, cov.data())) {
    return Status::Error("could not read the covariance from Ceres");
  }
  // Ceres fills row-major; the matrix is symmetric, so the layout does not matter.
  double sum_weight = 0.0, sum_meat = 0.0, sum_bread = 0.0;
  size_t n = 0;
  for (size_t d = 0; d < datasets_.size(); ++d) {
    for (double s : WhitenedSquaredNorms(d)) {
      double rho[3] = {s, 1.0, 0.0};
      if (loss_) loss_->Evaluate(s, rho);
      sum_weight += rho[1];
      sum_meat += rho[1] * rho[1] * s / 3.0;
      sum_bread += rho[1] + 2.0 * rho[2] * s / 3.0;
      ++n;
    }
  }
  const double components = 3.0 * n;
  if (components <= kNumLaserParams || sum_bread <= 0.0) {
    return Status::Error("too few intervals for a covariance");
  }
  const double mean_weight = sum_weight / n, mean_meat = sum_meat / n, mean_bread = sum_bread / n;
  covariance_scale_ = mean_weight * mean_meat / (mean_bread * mean_bread) * components /
                      (components - kNumLaserParams);
  return LaserParamMatrix(cov * covariance_scale_);
}

StatusOr<LaserParamMatrix> LaserProblem::SandwichCovariance() const {
  const int threads = std::max(1, options_.num_threads);
  std::vector<LaserParamMatrix> breads(threads, LaserParamMatrix::Zero());
  std::vector<LaserParamMatrix> meats(threads, LaserParamMatrix::Zero());
  std::atomic<bool> failed{false};
  ParallelChunks(cost_functions_.size(), threads, [&](size_t chunk, size_t begin, size_t end) {
    const double* parameters[2] = {odometry_, base_T_sensor_};
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> j_odometry, j_sensor;
    double* jacobians[2] = {j_odometry.data(), j_sensor.data()};
    Eigen::Matrix<double, 3, kNumLaserParams> j;
    Eigen::Vector3d r;
    for (size_t k = begin; k < end; ++k) {
      if (!cost_functions_[k]->Evaluate(parameters, r.data(), jacobians)) {
        failed = true;
        return;
      }
      j << j_odometry, j_sensor;
      const double s = r.squaredNorm();
      double rho[3] = {s, 1.0, 0.0};
      if (loss_) loss_->Evaluate(s, rho);
      const Eigen::Matrix<double, kNumLaserParams, 1> g = j.transpose() * r;
      breads[chunk] += rho[1] * j.transpose() * j + 2.0 * rho[2] * g * g.transpose();
      meats[chunk] += rho[1] * rho[1] * g * g.transpose();
    }
  });
  if (failed) return Status::Error("a residual could not be evaluated at the estimate");
  LaserParamMatrix bread = LaserParamMatrix::Zero(), meat = LaserParamMatrix::Zero();
  for (int c = 0; c < threads; ++c) {
    bread += breads[c];
    meat += meats[c];
  }
  const double n = 3.0 * cost_functions_.size();
  if (n <= kNumLaserParams) return Status::Error("too few intervals for a covariance");
  const Eigen::LDLT<LaserParamMatrix> ldlt(bread);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
    return Status::Error(
        "the information matrix is singular: the log does not determine all six "
        "parameters");
  }
  const LaserParamMatrix inverse = ldlt.solve(LaserParamMatrix::Identity());
  return LaserParamMatrix(inverse * meat * inverse * (n / (n - kNumLaserParams)));
}

Eigen::Vector3d RobustNoiseSigma(const std::vector<Eigen::Vector3d>& errors) {
  Eigen::Vector3d sigma = Eigen::Vector3d::Zero();
  if (errors.empty()) return Eigen::Vector3d::Ones();
  std::vector<double> values(errors.size());
  for (int j = 0; j < 3; ++j) {
    for (size_t k = 0; k < errors.size(); ++k) values[k] = errors[k](j);
    const size_t mid = values.size() / 2;
    std::nth_element(values.begin(), values.begin() + mid, values.end());
    const double median = values[mid];
    for (double& v : values) v = std::abs(v - median);
    std::nth_element(values.begin(), values.begin() + mid, values.end());
    // Floor: 1e-12 m or rad keeps noise-free data well-posed without affecting real data.
    sigma(j) = std::max(1.4826 * values[mid], 1e-12);
  }
  return sigma;
}

}  // namespace calib
