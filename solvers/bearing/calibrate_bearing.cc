#include <calib/core/bearing/bearing_log_io.h>
#include <calib/solvers/bearing/calibrate_bearing.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>

namespace calib {
namespace {

std::string Num(double value, int digits = 4) {
  std::ostringstream out;
  out.precision(digits);
  out << value;
  return out.str();
}

std::string RunName(int id) { return "run " + std::to_string(id); }

// A variance component is re-estimated only from at least this many degrees of freedom.
constexpr double kMinRedundancy = 2.0;
constexpr double kMinOdometryRedundancy = 0.5;

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Eigen::Vector2d Direction(double angle) {
  return Eigen::Vector2d(std::cos(angle), std::sin(angle));
}
double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// ---------------------------------------------------------------------------------------------
// The coarse search (SearchBearingSeed).

// Per run: the nominal wheel travels r·Δα from the previous bearing (0 for the first) and β.
struct SearchRun {
  std::vector<double> right_m, left_m;
  std::vector<double> beta;
};

struct SearchFit {
  double cost = std::numeric_limits<double>::infinity();
  double log_delta = 0.0, log_xi_b = 0.0;
  double c = 0.0;  // φ + ψ.
  Eigen::Vector2d mount = Eigen::Vector2d::Zero();
};

class SeedSearch {
 public:
  explicit SeedSearch(const BearingLog& log) : wheelbase_(log.meta.wheelbase_m) {
    const double r = log.meta.wheel_radius_m;
    for (const BearingRun& run : log.runs) {
      SearchRun s;
      double left0 = 0.0, right0 = 0.0;
      for (size_t j = 0; j < run.bearings.size(); ++j) {
        double left = 0.0, right = 0.0;
        InterpolateWheelAngles(run.odometry, run.bearings[j].t_s, &left, &right);
        s.right_m.push_back(j == 0 ? 0.0 : r * (right - right0));
        s.left_m.push_back(j == 0 ? 0.0 : r * (left - left0));
        s.beta.push_back(run.bearings[j].bearing_rad);
        left0 = left, right0 = right;
      }
      runs_.push_back(std::move(s));
    }
  }

  // Largest over the runs of how much the heading can swing when ln ξ, resp. δ, changes by one
  // (nominal δ = 1, ξ = 1/B): Σ|Δθ| and Σ|ΔsL|/B.
  void Sensitivities(double* per_log_xi, double* per_delta) const {
    *per_log_xi = 0.0, *per_delta = 0.0;
    for (const SearchRun& run : runs_) {
      double turn = 0.0, left = 0.0;
      for (size_t j = 0; j < run.beta.size(); ++j) {
        turn += std::abs(run.right_m[j] - run.left_m[j]) / wheelbase_;
        left += std::abs(run.left_m[j]) / wheelbase_;
      }
      *per_log_xi = std::max(*per_log_xi, turn);
      *per_delta = std::max(*per_delta, left);
    }
  }

  int num_bearings() const {
    int n = 0;
    for (const SearchRun& run : runs_) n += static_cast<int>(run.beta.size());
    return n;
  }

  // The fit for trial (δ, ξ): each run dead-reckoned from its first bearing (one arc per
  // interval), every `stride`-th bearing used.
  SearchFit Evaluate(double log_delta, double log_xi_b, int stride) const {
    SearchFit fit;
    fit.log_delta = log_delta;
    fit.log_xi_b = log_xi_b;
    const double delta = std::exp(log_delta);
    const double xi = std::exp(log_xi_b) / wheelbase_;
    std::vector<std::vector<Pose2d>> poses(runs_.size());
    std::vector<std::vector<double>> beta(runs_.size());
    for (size_t i = 0; i < runs_.size(); ++i) {
      const SearchRun& run = runs_[i];
      Pose2d pose = Pose2d::Zero();
      for (size_t j = 0; j < run.beta.size(); ++j) {
        if (j > 0) {
          const double right = run.right_m[j], left = delta * run.left_m[j];
          pose = Compose(pose, ArcDisplacement(0.5 * (right + left), xi * (right - left)));
        }
        if (j % stride == 0) {
          poses[i].push_back(pose);
          beta[i].push_back(run.beta[j]);
        }
      }
    }
    std::vector<std::vector<double>> weight(runs_.size());
    for (size_t i = 0; i < runs_.size(); ++i) weight[i].assign(poses[i].size(), 1.0);
    std::vector<Eigen::Vector2d> landmark(runs_.size(), Eigen::Vector2d::Zero());
    for (int pass = 0; pass < 2; ++pass) {
      // Unknowns: e_i = Q·L_i per run, f = Q·m, (cos c, sin c), with Q = R(−c − π/2); the row of
      // bearing j is [w | −u | cross(p, w), p·w] with u = u(β), w = R(θ)·u.
      using Matrix24 = Eigen::Matrix<double, 2, 4>;
      Eigen::Matrix4d s = Eigen::Matrix4d::Zero();
      std::vector<Eigen::Matrix2d> local_inverse(runs_.size());
      std::vector<Matrix24> cross_term(runs_.size());
      for (size_t i = 0; i < runs_.size(); ++i) {
        Eigen::Matrix2d ll = Eigen::Matrix2d::Zero();
        Matrix24 ls = Matrix24::Zero();
        for (size_t k = 0; k < poses[i].size(); ++k) {
          const Pose2d& p = poses[i][k];
          const Eigen::Vector2d u = Direction(beta[i][k]);
          const Eigen::Vector2d d = Direction(beta[i][k] + p(2));
          const Eigen::Vector2d pos = p.head<2>();
          const Eigen::Vector4d row_s(-u.x(), -u.y(), Cross(pos, d), pos.dot(d));
          const double wt = weight[i][k];
          ll += wt * d * d.transpose();
          ls += wt * d * row_s.transpose();
          s += wt * row_s * row_s.transpose();
        }
        ll.diagonal().array() += 1e-12 * ll.trace() + 1e-300;
        local_inverse[i] = ll.inverse();
        cross_term[i] = ls;
        s -= ls.transpose() * local_inverse[i] * ls;
      }
      Eigen::Matrix2d ff = s.topLeftCorner<2, 2>();
      ff.diagonal().array() += 1e-12 * ff.trace() + 1e-300;
      const Eigen::Matrix2d fc = s.topRightCorner<2, 2>();
      const Eigen::Matrix2d ff_inverse = ff.inverse();
      const Eigen::Matrix2d reduced =
          s.bottomRightCorner<2, 2>() - fc.transpose() * ff_inverse * fc;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(reduced);
      const Eigen::Vector2d v = eigen.eigenvectors().col(0);
      const Eigen::Vector2d f = -ff_inverse * fc * v;
      Eigen::Vector4d shared;
      shared << f, v;
      fit.c = std::atan2(v(1), v(0));
      const Eigen::Rotation2Dd back(fit.c + 0.5 * M_PI);  // Q⁻¹.
      fit.mount = back * f;
      double agreement = 0.0;
      for (size_t i = 0; i < runs_.size(); ++i) {
        landmark[i] = back * (-local_inverse[i] * cross_term[i] * shared);
        for (size_t k = 0; k < poses[i].size(); ++k) {
          const Pose2d& p = poses[i][k];
          const Eigen::Vector2d sensor = p.head<2>() + Eigen::Rotation2Dd(p(2)) * fit.mount;
          agreement += (landmark[i] - sensor).dot(Direction(beta[i][k] + p(2) + fit.c));
        }
      }
      if (agreement < 0.0) fit.c += M_PI;
      // Reweight so that the rows measure angles.
      double mean_distance = 0.0;
      int count = 0;
      for (size_t i = 0; i < runs_.size(); ++i) {
        for (size_t k = 0; k < poses[i].size(); ++k) {
          const Pose2d& p = poses[i][k];
          const Eigen::Vector2d sensor = p.head<2>() + Eigen::Rotation2Dd(p(2)) * fit.mount;
          weight[i][k] = (landmark[i] - sensor).norm();
          mean_distance += weight[i][k];
          ++count;
        }
      }
      mean_distance /= std::max(1, count);
      const double floor = 1e-3 * mean_distance + 1e-12;
      for (auto& ws : weight) {
        for (double& x : ws) x = 1.0 / std::pow(std::max(x, floor), 2);
      }
    }
    // The cost: mean squared bearing error (capped) of the fitted geometry.
    double cost = 0.0;
    int count = 0;
    for (size_t i = 0; i < runs_.size(); ++i) {
      for (size_t k = 0; k < poses[i].size(); ++k) {
        const Pose2d& p = poses[i][k];
        const Eigen::Vector2d sensor = p.head<2>() + Eigen::Rotation2Dd(p(2)) * fit.mount;
        const Eigen::Vector2d to = landmark[i] - sensor;
        const double predicted = std::atan2(to.y(), to.x()) - p(2) - fit.c;
        const double e = WrapAngle(beta[i][k] - predicted);
        cost += std::min(e * e, 0.25);
        ++count;
      }
    }
    fit.cost = count > 0 ? cost / count : std::numeric_limits<double>::infinity();
    if (!std::isfinite(fit.cost)) fit.cost = std::numeric_limits<double>::infinity();
    return fit;
  }

 private:
  double wheelbase_;
  std::vector<SearchRun> runs_;
};

// ---------------------------------------------------------------------------------------------

// E[z² | |z| < c] for a standard normal z: the variance kept by an inlier cut at c·σ.
double TruncatedVariance(double c) {
  const double density = std::exp(-0.5 * c * c) / std::sqrt(2.0 * M_PI);
  const double mass = std::erf(c / std::sqrt(2.0));
  return 1.0 - 2.0 * c * density / mass;
}

double RobustSigma(const std::vector<std::vector<double>>& errors) {
  std::vector<double> all;
  for (const auto& run : errors) {
    for (double e : run) all.push_back(std::abs(e));
  }
  if (all.empty()) return 0.0;
  const size_t mid = all.size() / 2;
  std::nth_element(all.begin(), all.begin() + mid, all.end());
  return 1.4826 * all[mid];
}

// How each bearing agrees with its neighbours in time: a quadratic in t fitted to up to
// `half_window` bearings on each side (unwrapped around their circular mean, trimmed at 3 MADs),
// its prediction error z normalized to unit variance for white noise; σ = 1.4826·median|z|
// estimates σβ without any model of the robot (plus the quadratic's own misfit, so from above).
struct BearingConsistency {
  std::vector<std::vector<double>> z;
  std::vector<double> run_sigma_rad;  // The same per run (a quadratic fits some runs worse).
  double sigma_rad = 0.0;
};

double MedianAbs(std::vector<double> values) {
  if (values.empty()) return 0.0;
  for (double& v : values) v = std::abs(v);
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

BearingConsistency CheckConsistency(const BearingLog& log, int half_window = 4) {
  BearingConsistency out;
  std::vector<double> all;
  for (const BearingRun& run : log.runs) {
    const int n = static_cast<int>(run.bearings.size());
    std::vector<double> z(n, 0.0);
    for (int j = 0; j < n; ++j) {
      std::vector<int> near;
      for (int k = std::max(0, j - half_window); k <= std::min(n - 1, j + half_window); ++k) {
        if (k != j) near.push_back(k);
      }
      if (near.size() < 5) continue;
      double cs = 0.0, sn = 0.0, span = 0.0;
      for (int k : near) {
        cs += std::cos(run.bearings[k].bearing_rad), sn += std::sin(run.bearings[k].bearing_rad);
        span = std::max(span, std::abs(run.bearings[k].t_s - run.bearings[j].t_s));
      }
      const double ref = std::atan2(sn, cs);
      std::vector<bool> keep(near.size(), true);
      double a = 0.0, variance = 1.0;
      for (int pass = 0; pass < 2; ++pass) {
        Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
        Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
        int used = 0;
        for (size_t m = 0; m < near.size(); ++m) {
          if (!keep[m]) continue;
          const double x = (run.bearings[near[m]].t_s - run.bearings[j].t_s) / span;
          const Eigen::Vector3d row(1.0, x, x * x);
          normal += row * row.transpose();
          rhs += row * WrapAngle(run.bearings[near[m]].bearing_rad - ref);
          ++used;
        }
        if (used < 4) break;
        const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
        const Eigen::Vector3d coef = ldlt.solve(rhs);
        a = coef(0);
        variance = ldlt.solve(Eigen::Vector3d::UnitX())(0);
        if (pass == 1) break;
        std::vector<double> residual;
        for (size_t m = 0; m < near.size(); ++m) {
          const double x = (run.bearings[near[m]].t_s - run.bearings[j].t_s) / span;
          residual.push_back(WrapAngle(run.bearings[near[m]].bearing_rad - ref) -
                             (coef(0) + coef(1) * x + coef(2) * x * x));
        }
        std::vector<double> magnitude;
        for (double r : residual) magnitude.push_back(std::abs(r));
        std::nth_element(magnitude.begin(), magnitude.begin() + magnitude.size() / 2,
                         magnitude.end());
        const double scale = std::max(1.4826 * magnitude[magnitude.size() / 2], 1e-12);
        for (size_t m = 0; m < near.size(); ++m) keep[m] = std::abs(residual[m]) <= 3.0 * scale;
      }
      z[j] = WrapAngle(run.bearings[j].bearing_rad - ref - a) / std::sqrt(1.0 + variance);
      all.push_back(z[j]);
    }
    out.run_sigma_rad.push_back(1.4826 * MedianAbs(z));
    out.z.push_back(z);
  }
  out.sigma_rad = 1.4826 * MedianAbs(all);
  return out;
}

}  // namespace

StatusOr<std::vector<Eigen::Vector2d>> SeedLandmarks(const BearingLog& log,
                                                     const BearingParams& params) {
  const double r = log.meta.wheel_radius_m;
  const double b = log.meta.wheelbase_m;
  const double rho = 0.5 / params.eta_per_m;
  const Eigen::Vector2d mount = rho * Direction(params.phi_rad);
  const double c = params.phi_rad + params.psi_rad;
  std::vector<Eigen::Vector2d> landmarks;
  for (const BearingRun& run : log.runs) {
    std::vector<Eigen::Vector2d> sensor, direction;
    Pose2d pose = Pose2d::Zero();
    double t = run.odometry.front().t_s;
    for (const BearingSample& s : run.bearings) {
      pose = Compose(pose, IntegrateEncoders(run.odometry, t, s.t_s, r, b, 1.0, params.delta,
                                             1.0 / (b * params.xi_per_m)));
      t = s.t_s;
      sensor.push_back(pose.head<2>() + Eigen::Rotation2Dd(pose(2)) * mount);
      direction.push_back(Direction(s.bearing_rad + pose(2) + c));
    }
    Eigen::Vector2d landmark = Eigen::Vector2d::Zero();
    std::vector<double> weight(sensor.size(), 1.0);
    for (int pass = 0; pass < 3; ++pass) {
      Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
      Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
      for (size_t j = 0; j < sensor.size(); ++j) {
        const Eigen::Vector2d row(direction[j].y(), -direction[j].x());
        normal += weight[j] * row * row.transpose();
        rhs += weight[j] * row * Cross(sensor[j], direction[j]);
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(normal);
      if (!(eigen.eigenvalues()(0) > 1e-9 * eigen.eigenvalues()(1))) {
        return Status::Error(RunName(run.id) +
                             ": the bearings do not locate the landmark (they are all parallel "
                             "in the odometry frame)");
      }
      landmark = normal.ldlt().solve(rhs);
      double mean = 0.0;
      for (size_t j = 0; j < sensor.size(); ++j) {
        weight[j] = (landmark - sensor[j]).norm();
        mean += weight[j] / sensor.size();
      }
      for (double& w : weight) w = 1.0 / std::pow(std::max(w, 1e-3 * mean + 1e-12), 2);
    }
    if (!(landmark.norm() > 0.0) || !landmark.allFinite()) {
      return Status::Error(RunName(run.id) + ": the bearings do not locate the landmark");
    }
    landmarks.push_back(landmark);
  }
  return landmarks;
}

StatusOr<BearingParams> SearchBearingSeed(const BearingLog& log,
                                          const BearingSearchOptions& options) {
  Status status = ValidateBearingLog(log);
  if (!status.ok()) return status;
  if (!(options.min_delta > 0.0 && options.max_delta > options.min_delta &&
        options.min_xi_b > 0.0 && options.max_xi_b > options.min_xi_b &&
        options.heading_tolerance_rad > 0.0 && options.max_grid_points >= 9)) {
    return Status::Error("invalid search options");
  }
  const SeedSearch search(log);
  // Grid steps that move the dead-reckoned heading by at most the tolerance anywhere in a run.
  double per_log_xi = 0.0, per_delta = 0.0;
  search.Sensitivities(&per_log_xi, &per_delta);
  const double d0 = std::log(options.min_delta), d1 = std::log(options.max_delta);
  const double x0 = std::log(options.min_xi_b), x1 = std::log(options.max_xi_b);
  double step_d = std::min(0.02, options.heading_tolerance_rad / std::max(per_delta, 1e-9));
  double step_x = std::min(0.02, options.heading_tolerance_rad / std::max(per_log_xi, 1e-9));
  int nd = static_cast<int>(std::ceil((d1 - d0) / step_d)) + 1;
  int nx = static_cast<int>(std::ceil((x1 - x0) / step_x)) + 1;
  if (static_cast<double>(nd) * nx > options.max_grid_points) {
    const double f = std::sqrt(static_cast<double>(nd) * nx / options.max_grid_points);
    nd = std::max(3, static_cast<int>(nd / f));
    nx = std::max(3, static_cast<int>(nx / f));
  }
  step_d = (d1 - d0) / (nd - 1);
  step_x = (x1 - x0) / (nx - 1);
  const int stride = std::max(1, (search.num_bearings() + options.max_search_bearings - 1) /
                                     std::max(1, options.max_search_bearings));
  std::vector<SearchFit> grid(static_cast<size_t>(nd) * nx);
  for (int i = 0; i < nd; ++i) {
    for (int j = 0; j < nx; ++j) {
      grid[i * nx + j] = search.Evaluate(d0 + i * step_d, x0 + j * step_x, stride);
    }
  }
  // Local minima of the grid, best first.
  std::vector<SearchFit> candidates;
  for (int i = 0; i < nd; ++i) {
    for (int j = 0; j < nx; ++j) {
      const double cost = grid[i * nx + j].cost;
      bool minimum = std::isfinite(cost);
      for (int di = -1; di <= 1 && minimum; ++di) {
        for (int dj = -1; dj <= 1 && minimum; ++dj) {
          const int a = i + di, b = j + dj;
          if ((di != 0 || dj != 0) && a >= 0 && a < nd && b >= 0 && b < nx &&
              grid[a * nx + b].cost < cost) {
            minimum = false;
          }
        }
      }
      if (minimum) candidates.push_back(grid[i * nx + j]);
    }
  }
  const auto by_cost = [](const SearchFit& a, const SearchFit& b) { return a.cost < b.cost; };
  std::sort(candidates.begin(), candidates.end(), by_cost);
  if (static_cast<int>(candidates.size()) > options.candidates) {
    candidates.resize(options.candidates);
  }
  if (candidates.empty()) {
    return Status::Error("the search found no calibration that explains the bearings");
  }
  // Refinement on every bearing, the step halving at each level.
  for (int level = 0; level < options.refine_levels; ++level) {
    if (level > 0) step_d *= 0.5, step_x *= 0.5;
    for (SearchFit& candidate : candidates) {
      SearchFit best;
      for (int i = -2; i <= 2; ++i) {
        for (int j = -2; j <= 2; ++j) {
          const SearchFit fit =
              search.Evaluate(candidate.log_delta + i * step_d, candidate.log_xi_b + j * step_x, 1);
          if (fit.cost < best.cost) best = fit;
        }
      }
      if (std::isfinite(best.cost)) candidate = best;
    }
  }
  std::sort(candidates.begin(), candidates.end(), by_cost);
  const SearchFit& best = candidates.front();
  const double rho = best.mount.norm();
  if (!(rho > 0.0) || !std::isfinite(rho)) {
    return Status::Error("the search placed the sensor at the robot's centre");
  }
  BearingParams p;
  p.delta = std::exp(best.log_delta);
  p.xi_per_m = std::exp(best.log_xi_b) / log.meta.wheelbase_m;
  p.phi_rad = std::atan2(best.mount.y(), best.mount.x());
  p.psi_rad = WrapAngle(best.c - p.phi_rad);
  p.eta_per_m = 0.5 / rho;
  return p;
}

StatusOr<BearingCalibrationResult> CalibrateBearing(const BearingLog& log,
                                                    const BearingCalibrationOptions& options) {
  Status status = ValidateBearingLog(log);
  if (!status.ok()) return status;
  const std::string source = log.source.empty() ? "bearing log" : log.source;
  const auto progress = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  if (options.bearing_sigma_rad && !(*options.bearing_sigma_rad > 0.0)) {
    return Status::Error("the bearing noise σβ must be positive");
  }
  if (options.encoder_noise_k && !(*options.encoder_noise_k >= 0.0)) {
    return Status::Error("the encoder noise K must be non-negative");
  }
  BearingCalibrationResult result;
  auto clock = std::chrono::steady_clock::now();
  const double min_sigma = 1e-8, max_sigma = 0.5, min_k = 1e-8;

  // Bearings that disagree with their neighbours in time are left out of the seeds (the closed
  // form and the search are least squares); the adjustment keeps them under its robust loss. The
  // neighbours' agreement also gives the scale of σβ whatever the seed.
  const BearingConsistency consistency = CheckConsistency(log);
  result.bearing_scatter_rad = consistency.sigma_rad;
  BearingLog seed_log = log;
  for (size_t i = 0; i < seed_log.runs.size(); ++i) {
    std::vector<BearingSample> kept;
    // Relative to the larger of the log's and the run's scatter, and never below 2°: only gross
    // outliers matter to the seeds.
    const double cut = std::max(
        options.seed_outlier_cut * std::max(consistency.sigma_rad, consistency.run_sigma_rad[i]),
        2.0 * M_PI / 180.0);
    for (size_t j = 0; j < log.runs[i].bearings.size(); ++j) {
      if (std::abs(consistency.z[i][j]) <= cut) {
        kept.push_back(log.runs[i].bearings[j]);
      }
    }
    if (kept.size() >= std::min<size_t>(8, log.runs[i].bearings.size())) {
      result.seed_excluded += static_cast<int>(log.runs[i].bearings.size() - kept.size());
      seed_log.runs[i].bearings = std::move(kept);
    }
  }

  BearingNoise noise;
  noise.encoder_k =
      std::max(options.encoder_noise_k.value_or(options.encoder_noise_k_floor), min_k);
  noise.bearing_sigma_rad =
      options.bearing_sigma_rad.value_or(std::clamp(consistency.sigma_rad, min_sigma, max_sigma));
  result.bearing_sigma_estimated = !options.bearing_sigma_rad.has_value();
  result.encoder_k_estimated = !options.encoder_noise_k.has_value();

  // Seeds in turn: the closed form (circular runs), then the search. A seed is kept when the
  // adjustment from it explains the bearings as well as their neighbours agree (its residuals'
  // robust scale within twice theirs); otherwise it led to a wrong minimum.
  std::unique_ptr<BearingProblem> problem;
  std::vector<Eigen::Vector2d> landmarks;
  std::string rejected;
  ceres::Solver::Summary summary;
  for (int attempt = 0; attempt < 2 && !problem; ++attempt) {
    BearingParams seed;
    std::string method;
    if (attempt == 0) {
      if (!options.use_closed_form) continue;
      MartinelliOptions cf_options = options.closed_form;
      cf_options.skip_non_circular_runs = true;
      StatusOr<MartinelliEstimate> cf = MartinelliClosedForm(seed_log, cf_options);
      if (!cf.ok() && seed_log.meta.initial_distance) {
        // The distance may be given for a run that is not a circle: the closed form without it.
        const std::optional<InitialDistance> distance = seed_log.meta.initial_distance;
        seed_log.meta.initial_distance.reset();
        StatusOr<MartinelliEstimate> retry = MartinelliClosedForm(seed_log, cf_options);
        seed_log.meta.initial_distance = distance;
        if (retry.ok()) cf = std::move(retry);
      }
      if (!cf.ok()) {
        result.closed_form_message = cf.message();
        continue;
      }
      result.has_closed_form = true;
      result.closed_form = *cf;
      seed = cf->params;
      method = "closed_form";
    } else {
      progress("searching for a seed");
      StatusOr<BearingParams> searched = SearchBearingSeed(seed_log, options.search);
      if (!searched.ok()) {
        rejected += (rejected.empty() ? "" : "; ") + searched.message();
        continue;
      }
      seed = *searched;
      method = "search";
    }
    StatusOr<std::vector<Eigen::Vector2d>> seed_landmarks = SeedLandmarks(seed_log, seed);
    if (!seed_landmarks.ok()) {
      rejected += (rejected.empty() ? "" : "; ") + seed_landmarks.message();
      continue;
    }
    auto candidate = std::make_unique<BearingProblem>(
        log, seed, DeadReckonedPoses(log, seed, *seed_landmarks), noise, options.adjustment);
    status = candidate->Solve(&summary);
    if (!status.ok()) {
      rejected += (rejected.empty() ? "" : "; ") + status.message();
      continue;
    }
    const double fit = RobustSigma(candidate->BearingErrors());
    if (!(fit <= options.max_fit_over_scatter * consistency.sigma_rad + 1e-6)) {
      const std::string why = "from the " + std::string(attempt == 0 ? "closed-form" : "search") +
                              " seed the adjustment leaves bearing residuals of " +
                              Num(fit * 180.0 / M_PI, 3) +
                              "° where neighbouring bearings agree to " +
                              Num(consistency.sigma_rad * 180.0 / M_PI, 3) + "°";
      if (attempt == 0) result.closed_form_message = why;
      rejected += (rejected.empty() ? "" : "; ") + why;
      progress(why);
      continue;
    }
    problem = std::move(candidate);
    landmarks = *seed_landmarks;
    result.seed = seed;
    result.seed_method = method;
    result.iterations = static_cast<int>(summary.iterations.size());
  }
  if (!problem) {
    std::string why = rejected;  // Holds the closed form's rejection when it ran.
    if (!result.has_closed_form && !result.closed_form_message.empty()) {
      why = "the closed form does not apply: " + result.closed_form_message +
            (why.empty() ? "" : "; " + why);
    }
    return Status::Error(source + ": no calibration explains the bearings" +
                         (why.empty() ? "" : " (" + why + ")"));
  }
  size_t distance_run = 0;
  if (log.meta.initial_distance) {
    const InitialDistance& d = *log.meta.initial_distance;
    distance_run =
        static_cast<size_t>(std::find_if(log.runs.begin(), log.runs.end(),
                                         [&](const BearingRun& r) { return r.id == d.run; }) -
                            log.runs.begin());
    result.has_seed_metric = true;
    result.seed_metric = result.seed_method == "closed_form" && result.closed_form.has_metric
                             ? result.closed_form.metric
                             : BearingMetricFromScaled(result.seed, landmarks[distance_run].norm(),
                                                       d.meters, log.meta.wheelbase_m);
  }
  result.seed_seconds = Seconds(clock);
  clock = std::chrono::steady_clock::now();

  // Noise levels by variance components, re-solving while they change.
  const double cut = std::sqrt(options.inlier_chi2);
  const double kept_variance = TruncatedVariance(cut);
  std::vector<std::vector<bool>> inlier;
  const auto classify = [&]() {
    inlier.clear();
    const std::vector<std::vector<double>> errors = problem->BearingErrors();
    for (const auto& run : errors) {
      std::vector<bool> flags;
      for (double e : run) flags.push_back(std::abs(e) <= cut * problem->noise().bearing_sigma_rad);
      inlier.push_back(flags);
    }
  };
  for (int round = 0; round < options.noise_rounds; ++round) {
    classify();
    StatusOr<BearingVarianceComponents> vc = problem->VarianceComponents(inlier);
    if (!vc.ok()) return Status::Error(source + ": " + vc.message());
    result.bearing_redundancy = vc->bearing_redundancy;
    result.odometry_redundancy = vc->odometry_redundancy;
    BearingNoise next = problem->noise();
    if (result.bearing_sigma_estimated && vc->bearing_redundancy >= kMinRedundancy) {
      next.bearing_sigma_rad =
          std::clamp(std::sqrt(vc->bearing_sum_sq_rad2 / vc->bearing_redundancy / kept_variance),
                     min_sigma, max_sigma);
    }
    if (result.encoder_k_estimated && vc->odometry_redundancy >= kMinOdometryRedundancy) {
      // A K too small makes the odometry rigid and leaves it few degrees of freedom, so that it
      // would never be corrected: the update runs from half a degree of freedom on. The fixed
      // point K = K·√(Σ‖L·e‖²/r) is approached slowly (the redundancy grows with K), so each
      // step is doubled in log K (over-relaxation), and kept within a factor of 3.
      const double ratio = vc->odometry_sum_sq / vc->odometry_redundancy;
      result.encoder_k_estimate = next.encoder_k * std::sqrt(ratio);
      next.encoder_k = std::max({min_k, options.encoder_noise_k_floor,
                                 next.encoder_k * std::clamp(ratio, 1.0 / 3.0, 3.0)});
    }
    const double change =
        std::max(std::abs(next.bearing_sigma_rad / problem->noise().bearing_sigma_rad - 1.0),
                 std::abs(next.encoder_k / problem->noise().encoder_k - 1.0));
    progress("noise round " + std::to_string(round + 1) + ": σβ = " +
             Num(next.bearing_sigma_rad * 180.0 / M_PI) + "°, K = " + Num(next.encoder_k));
    if (change < options.noise_tolerance) break;
    problem->SetNoise(next);
    problem->Relinearize();
    status = problem->Solve(&summary);
    if (!status.ok()) return Status::Error(source + ": " + status.message());
    result.iterations += static_cast<int>(summary.iterations.size());
    ++result.noise_rounds;
  }
  classify();
  result.noise = problem->noise();
  result.estimate = problem->params();
  result.poses = problem->poses();
  result.residuals_rad = problem->BearingErrors();
  result.adjustment_seconds = Seconds(clock);
  clock = std::chrono::steady_clock::now();

  // Covariance, and the metric set when a distance is known. When K comes from the data (above
  // its floor), from few degrees of freedom r, the covariance takes K at the upper end of its
  // one-sigma range, K²·(1 + √(2/r)): the uncertainty of K itself must not make sigmas too small.
  BearingNoise reported = problem->noise();
  if (result.encoder_k_estimated && result.odometry_redundancy >= kMinRedundancy &&
      reported.encoder_k > options.encoder_noise_k_floor) {
    reported.encoder_k *= std::sqrt(1.0 + std::sqrt(2.0 / result.odometry_redundancy));
    problem->SetNoise(reported);
  }
  result.covariance_encoder_k = reported.encoder_k;
  if (log.meta.initial_distance) {
    const InitialDistance& d = *log.meta.initial_distance;
    StatusOr<CorrectedCovariance<BearingScaledWithDistanceMatrix>> joint =
        problem->CalibrationCovarianceWithStartDistance(distance_run);
    if (!joint.ok()) return joint.status().Prefixed(source + ": ");
    result.covariance = joint->covariance.topLeftCorner<kNumBearingParams, kNumBearingParams>();
    Eigen::Matrix<double, kNumBearingMetricParams, kNumBearingParams + 1> jacobian;
    result.metric = BearingMetricFromScaled(result.estimate, problem->StartDistance(distance_run),
                                            d.meters, log.meta.wheelbase_m, &jacobian);
    result.metric_covariance = jacobian * joint->covariance * jacobian.transpose();
    result.metric_stddev = result.metric_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    result.has_metric = true;
    result.covariance_scale = joint->kappa;
  } else {
    StatusOr<CorrectedCovariance<BearingParamMatrix>> cov = problem->CalibrationCovariance();
    if (!cov.ok()) return cov.status().Prefixed(source + ": ");
    result.covariance = cov->covariance;
    result.covariance_scale = cov->kappa;
  }
  result.stddev = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  result.covariance_seconds = Seconds(clock);

  // A parameter the log barely determines is reported as an error, not as a number.
  const BearingParamVector value = ToVector(result.estimate);
  std::string weak;
  for (int i = 0; i < kNumBearingParams; ++i) {
    const bool angle = i == kBearingPhi || i == kBearingPsi;
    const double limit =
        angle ? options.max_angle_stddev_rad : options.max_relative_stddev * std::abs(value(i));
    if (!(result.stddev(i) <= limit)) {
      weak += (weak.empty() ? "" : ", ") + std::string(kBearingParamNames[i]) +
              " (σ = " + Num(result.stddev(i), 3) + ")";
    }
  }
  if (!weak.empty()) {
    return Status::Error(source + ": the log does not determine " + weak +
                         ": it needs circular runs at three or more distinct wheel-speed ratios, "
                         "or runs whose curvature varies, with the landmark in view");
  }

  // Summaries.
  for (size_t i = 0; i < log.runs.size(); ++i) {
    BearingRunSummary s;
    s.run = log.runs[i].id;
    s.bearings = static_cast<int>(log.runs[i].bearings.size());
    double sum = 0.0;
    for (size_t j = 0; j < inlier[i].size(); ++j) {
      if (!inlier[i][j]) continue;
      ++s.inliers;
      sum += result.residuals_rad[i][j] * result.residuals_rad[i][j];
    }
    s.rms_residual_rad = s.inliers > 0 ? std::sqrt(sum / s.inliers) : 0.0;
    s.start_distance = problem->StartDistance(i);
    if (result.has_closed_form) {
      for (const MartinelliRunEstimate& run : result.closed_form.runs) {
        if (run.run == s.run) s.circular = true, s.q = run.q;
      }
    }
    result.samples += s.bearings;
    result.inliers += s.inliers;
    result.runs.push_back(s);
  }
  return result;
}

}  // namespace calib
