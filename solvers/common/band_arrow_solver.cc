#include <calib/core/timing/banded_ldlt.h>
#include <calib/solvers/common/band_arrow_solver.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <thread>
#include <unordered_map>

namespace calib {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The largest residual block it takes (the timing-aware interval: 3 residuals, at most 16
// parameters in at most 10 blocks).
constexpr int kMaxResiduals = 4, kMaxColumns = 24, kMaxBlocks = 12;
// Reweighting overstates the curvature of a robust loss (its model gains less than the step
// does): after such a step, up to this many more of the same while the cost keeps falling.
constexpr int kExtensions = 3;

struct Block {
  double* values = nullptr;
  int size = 0;
  int tangent = 0;
  const ceres::Manifold* manifold = nullptr;
  int column = 0;  // Globals: first tangent column; latents: latent index.
  bool latent = false;
};

struct Term {
  const ceres::CostFunction* cost = nullptr;
  const ceres::LossFunction* loss = nullptr;
  std::vector<double*> values;
  std::vector<int> block;  // Index into the blocks, −1 for a constant block.
  int columns = 0;         // Tangent columns of its non-constant blocks.
};

// The normal equations H = JᵀWJ, g = Jᵀρ′r, split as globals (g) and latents (l, banded).
struct ArrowSystem {
  Eigen::MatrixXd h_gg, h_lg, band;
  Eigen::VectorXd g_g, g_l;
  double cost = 0.0;
  void Reset(int globals, int latents, int width) {
    h_gg = Eigen::MatrixXd::Zero(globals, globals);
    h_lg = Eigen::MatrixXd::Zero(latents, globals);
    band = Eigen::MatrixXd::Zero(width + 1, latents);
    g_g = Eigen::VectorXd::Zero(globals);
    g_l = Eigen::VectorXd::Zero(latents);
    cost = 0.0;
  }
  void Add(const ArrowSystem& o) {
    h_gg += o.h_gg, h_lg += o.h_lg, band += o.band, g_g += o.g_g, g_l += o.g_l, cost += o.cost;
  }
};

class BandArrowProblem {
 public:
  Status Build(const std::vector<double*>& latents, ceres::Problem* problem);
  // Cost (½Σρ) at the current values, with the normal equations when `system` is not null.
  bool Evaluate(ArrowSystem* system, int num_threads, double* cost) const;
  bool EvaluateRange(size_t begin, size_t end, ArrowSystem* system, double* cost) const;
  // Δ from (H + λD)Δ = −g; false when the damped system is not positive definite.
  // `global_step` is √(Δ_gᵀ S Δ_g), S the Schur complement of the latents.
  bool Step(const ArrowSystem& system, double lambda, Eigen::VectorXd* delta_g,
            Eigen::VectorXd* delta_l, double* model_decrease, double* global_step) const;
  void Save() const;
  void Restore() const;
  void Apply(const Eigen::VectorXd& delta_g, const Eigen::VectorXd& delta_l) const;
  double ParameterNorm() const;

  int globals() const { return globals_; }
  int latents() const { return static_cast<int>(latent_blocks_.size()); }
  int width() const { return width_; }

 private:
  std::vector<Block> blocks_;
  std::vector<int> latent_blocks_;
  std::vector<Term> terms_;
  int globals_ = 0, width_ = 0;
  mutable std::vector<double> saved_;
  mutable std::vector<ArrowSystem> parts_;  // Per evaluation thread beyond the first.
};

Status BandArrowProblem::Build(const std::vector<double*>& latents, ceres::Problem* problem) {
  std::unordered_map<const double*, int> index;
  for (double* value : latents) {
    if (problem->ParameterBlockSize(value) != 1 || problem->GetManifold(value) != nullptr) {
      return Status::Internal("a latent of the band-arrow solver is not a plain scalar block");
    }
    Block b;
    b.values = value, b.size = b.tangent = 1, b.latent = true;
    b.column = static_cast<int>(latent_blocks_.size());
    if (problem->IsParameterBlockConstant(value)) continue;
    index[value] = static_cast<int>(blocks_.size());
    latent_blocks_.push_back(static_cast<int>(blocks_.size()));
    blocks_.push_back(b);
  }
  std::vector<double*> all;
  problem->GetParameterBlocks(&all);
  for (double* value : all) {
    if (index.count(value) || problem->IsParameterBlockConstant(value)) continue;
    Block b;
    b.values = value;
    b.size = problem->ParameterBlockSize(value);
    b.manifold = problem->GetManifold(value);
    b.tangent = b.manifold ? b.manifold->TangentSize() : b.size;
    b.column = globals_;
    globals_ += b.tangent;
    index[value] = static_cast<int>(blocks_.size());
    blocks_.push_back(b);
  }
  std::vector<ceres::ResidualBlockId> ids;
  problem->GetResidualBlocks(&ids);
  for (const ceres::ResidualBlockId id : ids) {
    Term term;
    term.cost = problem->GetCostFunctionForResidualBlock(id);
    term.loss = problem->GetLossFunctionForResidualBlock(id);
    problem->GetParameterBlocksForResidualBlock(id, &term.values);
    int lo = static_cast<int>(latents.size()), hi = -1, columns = 0;
    for (double* value : term.values) {
      const auto it = index.find(value);
      term.block.push_back(it == index.end() ? -1 : it->second);
      if (it == index.end()) continue;
      const Block& b = blocks_[it->second];
      columns += b.tangent;
      if (b.latent) lo = std::min(lo, b.column), hi = std::max(hi, b.column);
    }
    if (hi >= lo) width_ = std::max(width_, hi - lo);
    term.columns = columns;
    int ambient = 0;
    for (double* value : term.values) ambient += problem->ParameterBlockSize(value);
    if (term.cost->num_residuals() > kMaxResiduals || ambient > kMaxColumns ||
        term.values.size() > static_cast<size_t>(kMaxBlocks)) {
      return Status::Internal("a residual of the band-arrow solver is larger than it supports");
    }
    terms_.push_back(std::move(term));
  }
  return Status::Ok();
}

bool BandArrowProblem::Evaluate(ArrowSystem* system, int num_threads, double* cost) const {
  const size_t n = terms_.size();
  const int threads = std::max(1, std::min<int>(num_threads, static_cast<int>(n / 256)));
  parts_.resize(threads);
  std::vector<double> costs(threads, 0.0);
  std::vector<char> ok(threads, 0);
  const auto run = [&](int t) {
    ArrowSystem* part = system ? (t == 0 ? system : &parts_[t]) : nullptr;
    if (part) part->Reset(globals_, latents(), width_);
    ok[t] = EvaluateRange(n * t / threads, n * (t + 1) / threads, part, &costs[t]);
  };
  std::vector<std::thread> workers;
  for (int t = 1; t < threads; ++t) workers.emplace_back(run, t);
  run(0);
  for (std::thread& w : workers) w.join();
  *cost = 0.0;
  for (int t = 0; t < threads; ++t) {
    if (!ok[t]) return false;
    *cost += costs[t];
    if (system && t > 0) system->Add(parts_[t]);
  }
  if (system) system->cost = *cost;
  return true;
}

bool BandArrowProblem::EvaluateRange(size_t begin, size_t end, ArrowSystem* system,
                                     double* cost) const {
  using Jacobian = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor,
                                 kMaxResiduals, kMaxColumns>;
  using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxColumns, kMaxColumns>;
  double r[kMaxResiduals];
  double ambient[kMaxResiduals * kMaxColumns];
  double* jacobians[kMaxBlocks];
  double plus[kMaxColumns * kMaxColumns];
  int column[kMaxColumns];
  bool is_latent[kMaxColumns];
  Jacobian jt;
  Square h;
  *cost = 0.0;
  for (size_t i = begin; i < end; ++i) {
    const Term& term = terms_[i];
    const int m = term.cost->num_residuals();
    if (system) {
      int at = 0;
      for (size_t p = 0; p < term.values.size(); ++p) {
        jacobians[p] = term.block[p] < 0 ? nullptr : ambient + at;
        if (term.block[p] >= 0) at += m * blocks_[term.block[p]].size;
      }
    }
    if (!term.cost->Evaluate(term.values.data(), r, system ? jacobians : nullptr)) return false;
    const Eigen::Map<const Eigen::VectorXd> res(r, m);
    const double s = res.squaredNorm();
    double rho[3] = {s, 1.0, 0.0};
    if (term.loss) term.loss->Evaluate(s, rho);
    if (!std::isfinite(rho[0])) return false;
    *cost += 0.5 * rho[0];
    if (!system) continue;
    // The tangent Jacobian, columns in the order of the term's blocks.
    int columns = 0;
    jt.resize(m, term.columns);
    for (size_t p = 0; p < term.values.size(); ++p) {
      if (term.block[p] < 0) continue;
      const Block& b = blocks_[term.block[p]];
      const Eigen::Map<const RowMatrix> j(jacobians[p], m, b.size);
      if (b.manifold) {
        b.manifold->PlusJacobian(b.values, plus);
        jt.middleCols(columns, b.tangent) =
            j * Eigen::Map<const RowMatrix>(plus, b.size, b.tangent);
      } else {
        jt.middleCols(columns, b.size) = j;
      }
      for (int c = 0; c < b.tangent; ++c) {
        column[columns + c] = b.column + c;
        is_latent[columns + c] = b.latent;
      }
      columns += b.tangent;
    }
    // Reweighted: H += ρ′JᵀJ, g += ρ′Jᵀr.
    const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxColumns, 1> jr = jt.transpose() * res;
    h.noalias() = rho[1] * (jt.transpose() * jt);
    for (int a = 0; a < columns; ++a) {
      const int ca = column[a];
      (is_latent[a] ? system->g_l(ca) : system->g_g(ca)) += rho[1] * jr(a);
      for (int b = 0; b < columns; ++b) {
        const int cb = column[b];
        if (!is_latent[a]) {
          if (!is_latent[b]) system->h_gg(ca, cb) += h(a, b);
        } else if (!is_latent[b]) {
          system->h_lg(ca, cb) += h(a, b);
        } else if (cb >= ca) {
          system->band(cb - ca, ca) += h(a, b);
        }
      }
    }
  }
  if (system) system->cost = *cost;
  return true;
}

bool BandArrowProblem::Step(const ArrowSystem& system, double lambda, Eigen::VectorXd* delta_g,
                            Eigen::VectorXd* delta_l, double* model_decrease,
                            double* global_step) const {
  // Marquardt's scaling, clamped as Ceres does.
  const Eigen::VectorXd d_g = system.h_gg.diagonal().cwiseMax(1e-6).cwiseMin(1e32);
  const Eigen::VectorXd d_l = system.band.row(0).transpose().cwiseMax(1e-6).cwiseMin(1e32);
  Eigen::MatrixXd band = system.band;
  band.row(0) += lambda * d_l.transpose();
  Eigen::MatrixXd c = system.h_gg;
  c.diagonal() += lambda * d_g;
  Eigen::MatrixXd x(latents(), globals_);
  Eigen::VectorXd y(latents());
  if (latents() > 0) {
    BandedLdlt ldlt;
    if (!ldlt.Compute(std::move(band))) return false;
    x = ldlt.Solve(system.h_lg);
    y = ldlt.Solve(system.g_l);
  }
  *delta_g = Eigen::VectorXd::Zero(globals_);
  *global_step = 0.0;
  if (globals_ > 0) {
    const Eigen::MatrixXd s = c - system.h_lg.transpose() * x;
    const Eigen::LDLT<Eigen::MatrixXd> schur(s);
    if (schur.info() != Eigen::Success || !(schur.vectorD().array() > 0.0).all()) return false;
    *delta_g = -schur.solve(system.g_g - system.h_lg.transpose() * y);
    *global_step = std::sqrt(std::max(0.0, delta_g->dot(s * *delta_g)));
  }
  *delta_l = -(y + x * *delta_g);
  if (!delta_g->allFinite() || !delta_l->allFinite()) return false;
  // With (H + λD)Δ = −g, the undamped model's decrease −gᵀΔ − ½ΔᵀHΔ is ½(−gᵀΔ + λΔᵀDΔ).
  const double gd = system.g_g.dot(*delta_g) + system.g_l.dot(*delta_l);
  const double dd = delta_g->cwiseAbs2().dot(d_g) + delta_l->cwiseAbs2().dot(d_l);
  *model_decrease = 0.5 * (-gd + lambda * dd);
  return true;
}

void BandArrowProblem::Save() const {
  saved_.clear();
  for (const Block& b : blocks_) saved_.insert(saved_.end(), b.values, b.values + b.size);
}

void BandArrowProblem::Restore() const {
  size_t at = 0;
  for (const Block& b : blocks_) {
    std::copy(saved_.begin() + at, saved_.begin() + at + b.size, b.values);
    at += b.size;
  }
}

void BandArrowProblem::Apply(const Eigen::VectorXd& delta_g, const Eigen::VectorXd& delta_l) const {
  std::vector<double> x;
  for (const Block& b : blocks_) {
    if (b.latent) {
      b.values[0] += delta_l(b.column);
    } else if (b.manifold) {
      x.assign(b.values, b.values + b.size);
      b.manifold->Plus(x.data(), delta_g.data() + b.column, b.values);
    } else {
      for (int i = 0; i < b.size; ++i) b.values[i] += delta_g(b.column + i);
    }
  }
}

double BandArrowProblem::ParameterNorm() const {
  double sum = 0.0;
  for (const Block& b : blocks_) {
    for (int i = 0; i < b.size; ++i) sum += b.values[i] * b.values[i];
  }
  return std::sqrt(sum);
}

// Levenberg–Marquardt on a built arrow.
Status SolveArrow(const BandArrowOptions& options, const std::string& what,
                  const BandArrowProblem& arrow, BandArrowSummary* summary) {
  BandArrowSummary out;
  out.band_width = arrow.width();
  ArrowSystem system;
  double cost = 0.0;
  if (!arrow.Evaluate(&system, options.num_threads, &cost) || !std::isfinite(cost)) {
    return Status::NotConverged(what + " failed: the cost is not finite at the starting point");
  }
  out.initial_cost = cost;
  double lambda = 1e-4, nu = 2.0;
  bool fresh = true;        // `system` is at the current point.
  int settled_globals = 0;  // Accepted steps in a row below options.global_step_tolerance.
  for (; out.iterations < options.max_iterations && !out.converged; ++out.iterations) {
    if (!fresh && !arrow.Evaluate(&system, options.num_threads, &cost)) {
      return Status::NotConverged(what + " failed: the Jacobian could not be evaluated");
    }
    fresh = true;
    if (std::max(system.g_g.lpNorm<Eigen::Infinity>(), system.g_l.lpNorm<Eigen::Infinity>()) <=
        options.gradient_tolerance) {
      out.converged = true;
      break;
    }
    Eigen::VectorXd delta_g, delta_l;
    double model_decrease = 0.0, global_step = 0.0;
    if (!arrow.Step(system, lambda, &delta_g, &delta_l, &model_decrease, &global_step) ||
        !(model_decrease > 0.0)) {
      lambda *= nu, nu *= 2.0;
      continue;
    }
    const double step_norm = std::sqrt(delta_g.squaredNorm() + delta_l.squaredNorm());
    if (step_norm <=
        options.parameter_tolerance * (arrow.ParameterNorm() + options.parameter_tolerance)) {
      out.converged = true;
      break;
    }
    arrow.Save();
    arrow.Apply(delta_g, delta_l);
    double trial = 0.0;
    const bool ok = arrow.Evaluate(nullptr, options.num_threads, &trial) && std::isfinite(trial);
    const double ratio = ok ? (cost - trial) / model_decrease : -1.0;
    if (ratio > 1e-3) {
      // The model underestimated the gain (reweighting overstates the curvature of a robust loss):
      // go on along the same step while the cost keeps falling.
      for (int e = 0; e < kExtensions && ratio > 1.2; ++e) {
        arrow.Apply(delta_g, delta_l);
        double further = 0.0;
        if (!(arrow.Evaluate(nullptr, options.num_threads, &further) && further < trial)) {
          arrow.Apply(-delta_g, -delta_l);
          break;
        }
        trial = further;
      }
      const double decrease = cost - trial;
      cost = trial;
      fresh = false;
      lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3));
      nu = 2.0;
      settled_globals = global_step < options.global_step_tolerance ? settled_globals + 1 : 0;
      out.converged = decrease <= options.function_tolerance * cost || settled_globals >= 2;
    } else {
      arrow.Restore();
      lambda *= nu, nu *= 2.0;
    }
    if (lambda > 1e32) break;
  }
  out.final_cost = cost;
  if (summary) *summary = out;
  return Status::Ok();
}

}  // namespace

struct BandArrowSolver::Structure {
  BandArrowProblem arrow;
};

BandArrowSolver::BandArrowSolver() = default;
BandArrowSolver::~BandArrowSolver() = default;

Status BandArrowSolver::Build(const std::vector<double*>& latents, ceres::Problem* problem) {
  structure_ = std::make_unique<Structure>();
  const Status built = structure_->arrow.Build(latents, problem);
  if (!built.ok()) structure_.reset();
  return built;
}

Status BandArrowSolver::Solve(const BandArrowOptions& options, const std::string& what,
                              BandArrowSummary* summary) const {
  if (!structure_) return Status::Internal(what + ": the band-arrow solver was not built");
  return SolveArrow(options, what, structure_->arrow, summary);
}

Status SolveBandArrow(const BandArrowOptions& options, const std::vector<double*>& latents,
                      const std::string& what, ceres::Problem* problem, BandArrowSummary* summary) {
  BandArrowSolver solver;
  CALIB_RETURN_IF_ERROR(solver.Build(latents, problem));
  return solver.Solve(options, what, summary);
}

}  // namespace calib
