#include <calib/core/bearing/bearing_log_io.h>
#include <calib/solvers/bearing/bearing_seed_search.h>
#include <calib/solvers/bearing/bearing_text.h>
#include <calib/solvers/common/parallel_chunks.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace calib {
namespace {

Eigen::Vector2d Direction(double angle) {
  return Eigen::Vector2d(std::cos(angle), std::sin(angle));
}
double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

bool Kept(const std::vector<std::vector<bool>>* keep, size_t run, size_t bearing) {
  return keep == nullptr || (*keep)[run][bearing];
}

// (cos a, sin a) as a vector, and a vector turned by the angle whose (cos, sin) is `turn`.
Eigen::Vector2d Rotate(const Eigen::Vector2d& turn, const Eigen::Vector2d& v) {
  return Eigen::Vector2d(turn.x() * v.x() - turn.y() * v.y(), turn.y() * v.x() + turn.x() * v.y());
}

// One interval's turn a: sin a, 1 − cos a, and both over a (the arc's displacement), by their
// series for the small turns between bearings (the search evaluates every interval at every grid
// point: libm's sincos and the divisions were most of its time), by libm beyond.
struct Turn {
  double sine, versine, sine_over_a, versine_over_a;
};
Turn SmallTurn(double a) {
  if (std::abs(a) > 0.5) {
    const double sine = std::sin(a), versine = 1.0 - std::cos(a);
    return {sine, versine, sine / a, versine / a};
  }
  const double q = a * a;  // Truncation below 1e-17 relative for |a| ≤ 0.5.
  constexpr double k6 = 1.0 / 6, k20 = 1.0 / 20, k42 = 1.0 / 42, k72 = 1.0 / 72, k110 = 1.0 / 110,
                   k156 = 1.0 / 156, k12 = 1.0 / 12, k30 = 1.0 / 30, k56 = 1.0 / 56, k90 = 1.0 / 90,
                   k132 = 1.0 / 132;
  const double so =
      1 - q * k6 * (1 - q * k20 * (1 - q * k42 * (1 - q * k72 * (1 - q * k110 * (1 - q * k156)))));
  const double vo =
      0.5 * a * (1 - q * k12 * (1 - q * k30 * (1 - q * k56 * (1 - q * k90 * (1 - q * k132)))));
  return {a * so, a * vo, so, vo};
}

// Per run: the nominal wheel travels r·Δα from the previous bearing (0 for the first), β and
// its direction u(β).
struct SearchRun {
  std::vector<double> right_m, left_m;
  std::vector<double> beta;
  std::vector<Eigen::Vector2d> u;
};

struct SearchFit {
  double cost = std::numeric_limits<double>::infinity();
  double log_delta = 0.0, log_xi_b = 0.0;
  double c = 0.0;  // φ + ψ.
  Eigen::Vector2d mount = Eigen::Vector2d::Zero();
};

// A dead-reckoned pose at a used bearing: position, heading as (cos θ, sin θ), and the bearing.
struct PathPoint {
  Eigen::Vector2d position, heading;
  double beta = 0.0;
  Eigen::Vector2d u;  // u(β).
};

// The dead-reckoned poses of every run at its (used) bearings.
struct SearchPaths {
  std::vector<std::vector<PathPoint>> points;

  static Eigen::Vector2d Sensor(const PathPoint& p, const SearchFit& fit) {
    return p.position + Rotate(p.heading, fit.mount);
  }
};

// One weighted least-squares pass of the linear bearing condition: c, the mount and each run's
// landmark. Unknowns: e_i = Q·L_i per run, f = Q·m, (cos c, sin c), with Q = R(−c − π/2); the row
// of bearing j is [w | −u | cross(p, w), p·w] with u = u(β), w = R(θ)·u.
void SolveGeometry(const SearchPaths& paths, const std::vector<std::vector<double>>& weight,
                   SearchFit* fit, std::vector<Eigen::Vector2d>* landmark) {
  using Matrix24 = Eigen::Matrix<double, 2, 4>;
  const size_t runs = paths.points.size();
  Eigen::Matrix4d s = Eigen::Matrix4d::Zero();
  std::vector<Eigen::Matrix2d> local_inverse(runs);
  std::vector<Matrix24> cross_term(runs);
  for (size_t i = 0; i < runs; ++i) {
    Eigen::Matrix2d ll = Eigen::Matrix2d::Zero();
    Matrix24 ls = Matrix24::Zero();
    for (size_t k = 0; k < paths.points[i].size(); ++k) {
      const PathPoint& p = paths.points[i][k];
      const Eigen::Vector2d d = Rotate(p.heading, p.u);
      const Eigen::Vector4d row_s(-p.u.x(), -p.u.y(), Cross(p.position, d), p.position.dot(d));
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
  const Eigen::Matrix2d reduced = s.bottomRightCorner<2, 2>() - fc.transpose() * ff_inverse * fc;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(reduced);
  const Eigen::Vector2d v = eigen.eigenvectors().col(0);
  const Eigen::Vector2d f = -ff_inverse * fc * v;
  Eigen::Vector4d shared;
  shared << f, v;
  fit->c = std::atan2(v(1), v(0));
  const Eigen::Rotation2Dd back(fit->c + 0.5 * M_PI);  // Q⁻¹.
  fit->mount = back * f;
  const Eigen::Vector2d turn_c = Direction(fit->c);
  double agreement = 0.0;
  for (size_t i = 0; i < runs; ++i) {
    (*landmark)[i] = back * (-local_inverse[i] * cross_term[i] * shared);
    for (const PathPoint& p : paths.points[i]) {
      agreement += ((*landmark)[i] - SearchPaths::Sensor(p, *fit))
                       .dot(Rotate(turn_c, Rotate(p.heading, p.u)));
    }
  }
  if (agreement < 0.0) fit->c += M_PI;
}

// Weights 1/distance² so that the rows measure angles (distances floored at 1e-3 of their mean).
void ReweightByDistance(const SearchPaths& paths, const SearchFit& fit,
                        const std::vector<Eigen::Vector2d>& landmark,
                        std::vector<std::vector<double>>* weight) {
  double mean_distance = 0.0;
  int count = 0;
  for (size_t i = 0; i < paths.points.size(); ++i) {
    for (size_t k = 0; k < paths.points[i].size(); ++k) {
      (*weight)[i][k] = (landmark[i] - SearchPaths::Sensor(paths.points[i][k], fit)).norm();
      mean_distance += (*weight)[i][k];
      ++count;
    }
  }
  mean_distance /= std::max(1, count);
  const double floor = 1e-3 * mean_distance + 1e-12;
  for (auto& ws : *weight) {
    for (double& x : ws) x = 1.0 / std::pow(std::max(x, floor), 2);
  }
}

// The cost: mean squared bearing error (capped) of the fitted geometry.
double BearingCost(const SearchPaths& paths, const SearchFit& fit,
                   const std::vector<Eigen::Vector2d>& landmark) {
  double cost = 0.0;
  int count = 0;
  for (size_t i = 0; i < paths.points.size(); ++i) {
    for (const PathPoint& p : paths.points[i]) {
      // The landmark's direction in the robot frame: R(−θ)·(L − sensor).
      const Eigen::Vector2d to = landmark[i] - SearchPaths::Sensor(p, fit);
      const Eigen::Vector2d back(p.heading.x(), -p.heading.y());
      const Eigen::Vector2d local = Rotate(back, to);
      const double predicted = std::atan2(local.y(), local.x()) - fit.c;
      const double e = WrapAngle(p.beta - predicted);
      cost += std::min(e * e, 0.25);
      ++count;
    }
  }
  const double mean = count > 0 ? cost / count : std::numeric_limits<double>::infinity();
  return std::isfinite(mean) ? mean : std::numeric_limits<double>::infinity();
}

class SeedSearch {
 public:
  SeedSearch(const BearingLog& log, const std::vector<std::vector<bool>>* keep)
      : wheelbase_(log.meta.wheelbase_m) {
    const double r = log.meta.wheel_radius_m;
    for (size_t i = 0; i < log.runs.size(); ++i) {
      const BearingRun& run = log.runs[i];
      SearchRun s;
      double left0 = 0.0, right0 = 0.0;
      for (size_t j = 0; j < run.bearings.size(); ++j) {
        if (!Kept(keep, i, j)) continue;
        const bool first = s.beta.empty();
        double left = 0.0, right = 0.0;
        InterpolateWheelAngles(run.odometry, run.bearings[j].t_s, &left, &right);
        s.right_m.push_back(first ? 0.0 : r * (right - right0));
        s.left_m.push_back(first ? 0.0 : r * (left - left0));
        s.beta.push_back(run.bearings[j].bearing_rad);
        s.u.push_back(Direction(run.bearings[j].bearing_rad));
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
  // interval), every `stride`-th bearing used; two passes, the second reweighted by distance.
  SearchFit Evaluate(double log_delta, double log_xi_b, int stride) const {
    SearchFit fit;
    fit.log_delta = log_delta;
    fit.log_xi_b = log_xi_b;
    const SearchPaths paths =
        DeadReckon(std::exp(log_delta), std::exp(log_xi_b) / wheelbase_, stride);
    std::vector<std::vector<double>> weight(runs_.size());
    for (size_t i = 0; i < runs_.size(); ++i) weight[i].assign(paths.points[i].size(), 1.0);
    std::vector<Eigen::Vector2d> landmark(runs_.size(), Eigen::Vector2d::Zero());
    for (int pass = 0; pass < 2; ++pass) {
      SolveGeometry(paths, weight, &fit, &landmark);
      ReweightByDistance(paths, fit, landmark, &weight);
    }
    fit.cost = BearingCost(paths, fit, landmark);
    return fit;
  }

 private:
  // Each interval one arc: the displacement (d·sin a/a, d·(1 − cos a)/a) turned by the heading.
  SearchPaths DeadReckon(double delta, double xi, int stride) const {
    SearchPaths paths;
    paths.points.resize(runs_.size());
    for (size_t i = 0; i < runs_.size(); ++i) {
      const SearchRun& run = runs_[i];
      Eigen::Vector2d position = Eigen::Vector2d::Zero(), heading(1.0, 0.0);
      for (size_t j = 0; j < run.beta.size(); ++j) {
        if (j > 0) {
          const double right = run.right_m[j], left = delta * run.left_m[j];
          const double d = 0.5 * (right + left), a = xi * (right - left);
          const Turn turn = SmallTurn(a);
          position +=
              Rotate(heading, Eigen::Vector2d(d * turn.sine_over_a, d * turn.versine_over_a));
          heading = Rotate(heading, Eigen::Vector2d(1.0 - turn.versine, turn.sine));
          if (j % 256 == 0) heading.normalize();
        }
        if (j % stride == 0) {
          paths.points[i].push_back(PathPoint{position, heading, run.beta[j], run.u[j]});
        }
      }
    }
    return paths;
  }

  double wheelbase_;
  std::vector<SearchRun> runs_;
};

// The grid over (ln δ, ln ξB): steps that move the dead-reckoned heading by at most the tolerance
// anywhere in a run, coarser when there would be more than max_grid_points.
struct SearchGrid {
  double d0 = 0.0, x0 = 0.0, step_d = 0.0, step_x = 0.0;
  int nd = 0, nx = 0;
};

SearchGrid MakeGrid(const SeedSearch& search, const BearingSearchOptions& options) {
  double per_log_xi = 0.0, per_delta = 0.0;
  search.Sensitivities(&per_log_xi, &per_delta);
  SearchGrid g;
  g.d0 = std::log(options.min_delta);
  const double d1 = std::log(options.max_delta);
  g.x0 = std::log(options.min_xi_b);
  const double x1 = std::log(options.max_xi_b);
  g.step_d = std::min(0.02, options.heading_tolerance_rad / std::max(per_delta, 1e-9));
  g.step_x = std::min(0.02, options.heading_tolerance_rad / std::max(per_log_xi, 1e-9));
  g.nd = static_cast<int>(std::ceil((d1 - g.d0) / g.step_d)) + 1;
  g.nx = static_cast<int>(std::ceil((x1 - g.x0) / g.step_x)) + 1;
  if (static_cast<double>(g.nd) * g.nx > options.max_grid_points) {
    const double f = std::sqrt(static_cast<double>(g.nd) * g.nx / options.max_grid_points);
    g.nd = std::max(3, static_cast<int>(g.nd / f));
    g.nx = std::max(3, static_cast<int>(g.nx / f));
  }
  g.step_d = (d1 - g.d0) / (g.nd - 1);
  g.step_x = (x1 - g.x0) / (g.nx - 1);
  return g;
}

// The local minima of the grid, best first, at most `count`.
std::vector<SearchFit> GridMinima(const SeedSearch& search, const SearchGrid& g, int stride,
                                  int count, int num_threads) {
  std::vector<SearchFit> grid(static_cast<size_t>(g.nd) * g.nx);
  ParallelChunks(grid.size(), num_threads, 1, [&](int, size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      const int i = static_cast<int>(k) / g.nx, j = static_cast<int>(k) % g.nx;
      grid[k] = search.Evaluate(g.d0 + i * g.step_d, g.x0 + j * g.step_x, stride);
    }
  });
  std::vector<SearchFit> candidates;
  for (int i = 0; i < g.nd; ++i) {
    for (int j = 0; j < g.nx; ++j) {
      const double cost = grid[i * g.nx + j].cost;
      bool minimum = std::isfinite(cost);
      for (int di = -1; di <= 1 && minimum; ++di) {
        for (int dj = -1; dj <= 1 && minimum; ++dj) {
          const int a = i + di, b = j + dj;
          if ((di != 0 || dj != 0) && a >= 0 && a < g.nd && b >= 0 && b < g.nx &&
              grid[a * g.nx + b].cost < cost) {
            minimum = false;
          }
        }
      }
      if (minimum) candidates.push_back(grid[i * g.nx + j]);
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const SearchFit& a, const SearchFit& b) { return a.cost < b.cost; });
  if (static_cast<int>(candidates.size()) > count) candidates.resize(count);
  return candidates;
}

// Refinement of each candidate on every bearing, 5×5 around it, the step halving at each level.
void RefineCandidates(const SeedSearch& search, SearchGrid g, int levels, int num_threads,
                      std::vector<SearchFit>* candidates) {
  for (int level = 0; level < levels; ++level) {
    if (level > 0) g.step_d *= 0.5, g.step_x *= 0.5;
    for (SearchFit& candidate : *candidates) {
      std::vector<SearchFit> fits(25);
      ParallelChunks(fits.size(), num_threads, 1, [&](int, size_t begin, size_t end) {
        for (size_t k = begin; k < end; ++k) {
          const int i = static_cast<int>(k) / 5 - 2, j = static_cast<int>(k) % 5 - 2;
          fits[k] = search.Evaluate(candidate.log_delta + i * g.step_d,
                                    candidate.log_xi_b + j * g.step_x, 1);
        }
      });
      SearchFit best;
      for (const SearchFit& fit : fits) {
        if (fit.cost < best.cost) best = fit;  // The first of equals, as in a serial loop.
      }
      if (std::isfinite(best.cost)) candidate = best;
    }
  }
  std::sort(candidates->begin(), candidates->end(),
            [](const SearchFit& a, const SearchFit& b) { return a.cost < b.cost; });
}

}  // namespace

StatusOr<std::vector<Eigen::Vector2d>> SeedLandmarks(const BearingLog& log,
                                                     const BearingParams& params,
                                                     const std::vector<std::vector<bool>>* keep) {
  const double r = log.meta.wheel_radius_m;
  const double b = log.meta.wheelbase_m;
  const double rho = 0.5 / params.eta_per_m;
  const Eigen::Vector2d mount = rho * Direction(params.phi_rad);
  const double c = params.phi_rad + params.psi_rad;
  std::vector<Eigen::Vector2d> landmarks;
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const BearingRun& run = log.runs[i];
    std::vector<Eigen::Vector2d> sensor, direction;
    Pose2d pose = Pose2d::Zero();
    double t = run.odometry.front().t_s;
    for (size_t j = 0; j < run.bearings.size(); ++j) {
      if (!Kept(keep, i, j)) continue;
      const BearingSample& s = run.bearings[j];
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
        return Status::NotObservable(RunName(run.id) +
                                     ": the bearings do not locate the landmark (they are all "
                                     "parallel in the odometry frame)");
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
      return Status::NotObservable(RunName(run.id) + ": the bearings do not locate the landmark");
    }
    landmarks.push_back(landmark);
  }
  return landmarks;
}

StatusOr<BearingParams> SearchBearingSeed(const BearingLog& log,
                                          const BearingSearchOptions& options) {
  CALIB_RETURN_IF_ERROR(ValidateBearingLog(log));
  return SearchBearingSeedOf(log, nullptr, options);
}

StatusOr<BearingParams> SearchBearingSeedOf(const BearingLog& log,
                                            const std::vector<std::vector<bool>>* keep,
                                            const BearingSearchOptions& options) {
  if (!(options.min_delta > 0.0 && options.max_delta > options.min_delta &&
        options.min_xi_b > 0.0 && options.max_xi_b > options.min_xi_b &&
        options.heading_tolerance_rad > 0.0 && options.max_grid_points >= 9)) {
    return Status::InvalidInput("invalid search options");
  }
  const SeedSearch search(log, keep);
  const SearchGrid grid = MakeGrid(search, options);
  const int stride = std::max(1, (search.num_bearings() + options.max_search_bearings - 1) /
                                     std::max(1, options.max_search_bearings));
  std::vector<SearchFit> candidates =
      GridMinima(search, grid, stride, options.candidates, options.num_threads);
  if (candidates.empty()) {
    return Status::NotObservable("the search found no calibration that explains the bearings");
  }
  RefineCandidates(search, grid, options.refine_levels, options.num_threads, &candidates);
  const SearchFit& best = candidates.front();
  const double rho = best.mount.norm();
  if (!(rho > 0.0) || !std::isfinite(rho)) {
    return Status::NotObservable("the search placed the sensor at the robot's centre");
  }
  BearingParams p;
  p.delta = std::exp(best.log_delta);
  p.xi_per_m = std::exp(best.log_xi_b) / log.meta.wheelbase_m;
  p.phi_rad = std::atan2(best.mount.y(), best.mount.x());
  p.psi_rad = WrapAngle(best.c - p.phi_rad);
  p.eta_per_m = 0.5 / rho;
  return p;
}

}  // namespace calib
