#include <calib/core/timing/banded_ldlt.h>
#include <calib/solvers/common/band_arrow_problem.h>
#include <calib/solvers/common/parallel_chunks.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace calib {
namespace band_arrow_internal {
namespace {

// How many residuals ahead the evaluation prefetches a cost function.
constexpr size_t kPrefetchAhead = 4;

}  // namespace

Status BandArrowProblem::Build(const std::vector<double*>& latents, ceres::Problem* problem) {
  return Build(latents, ArrowTerms::FromProblem(*problem));
}

Status BandArrowProblem::Build(const std::vector<double*>& latents, const ArrowTerms& terms) {
  std::unordered_map<const double*, int> listed;  // Into terms.blocks.
  listed.reserve(terms.blocks.size());
  for (size_t i = 0; i < terms.blocks.size(); ++i) listed.emplace(terms.blocks[i].values, i);
  const auto make_block = [&](const double* value, bool latent, Block* b) {
    const auto it = listed.find(value);
    if (it == listed.end()) return false;
    const ArrowTerms::Block& listed_block = terms.blocks[it->second];
    if (listed_block.constant) return false;
    b->values = listed_block.values, b->size = listed_block.size, b->latent = latent;
    b->manifold = listed_block.manifold;
    b->tangent = b->manifold ? b->manifold->TangentSize() : b->size;
    return b->tangent > 0;
  };
  std::unordered_map<const double*, int>& index = block_index_;
  index.reserve(terms.blocks.size());
  for (double* value : latents) {
    Block b;
    if (!make_block(value, true, &b)) continue;
    b.column = latent_columns_;
    latent_columns_ += b.tangent;
    index[value] = static_cast<int>(blocks_.size());
    latent_blocks_.push_back(static_cast<int>(blocks_.size()));
    blocks_.push_back(b);
  }
  for (const ArrowTerms::Block& listed_block : terms.blocks) {
    Block b;
    if (index.count(listed_block.values) || !make_block(listed_block.values, false, &b)) continue;
    b.column = globals_;
    globals_ += b.tangent;
    index[listed_block.values] = static_cast<int>(blocks_.size());
    blocks_.push_back(b);
  }
  terms_.reserve(terms.num_residuals());
  for (size_t i = 0; i < terms.num_residuals(); ++i) {
    Term term;
    term.index = static_cast<int>(terms_.size());
    term.cost = terms.costs[i];
    term.loss = terms.losses[i];
    double* const* values = terms.values.data() + terms.first_value[i];
    const int num_values = terms.first_value[i + 1] - terms.first_value[i];
    const std::vector<int32_t>& sizes = term.cost->parameter_block_sizes();
    int ambient = 0;
    for (const int32_t size : sizes) ambient += size;
    if (term.cost->num_residuals() > kMaxResiduals || ambient > kMaxColumns ||
        num_values > kMaxBlocks || num_values != static_cast<int>(sizes.size())) {
      return Status::Internal("a residual of the band-arrow solver is larger than it supports");
    }
    term.first_block = static_cast<int>(term_values_.size());
    term.num_blocks = num_values;
    term.first_column = static_cast<int>(term_column_.size());
    for (int v = 0; v < num_values; ++v) {
      double* value = values[v];
      const auto it = index.find(value);
      const int block = it == index.end() ? -1 : it->second;
      if (block < 0 && !listed.count(value)) {
        return Status::Internal("a residual of the band-arrow solver uses an unlisted block");
      }
      term_values_.push_back(value);
      term_block_.push_back(block);
      if (block >= 0 && !blocks_[block].latent) term.columns += blocks_[block].tangent;
    }
    term.globals = term.columns;
    int lo = latent_columns_, hi = -1;
    term_column_.resize(term.first_column + ambient);
    int global_at = 0;
    for (int p = 0; p < term.num_blocks; ++p) {
      const int block = term_block_[term.first_block + p];
      if (block < 0) {
        term_offset_.push_back(-1);
        continue;
      }
      const Block& b = blocks_[block];
      int& at = b.latent ? term.columns : global_at;
      term_offset_.push_back(at);
      for (int c = 0; c < b.tangent; ++c) term_column_[term.first_column + at + c] = b.column + c;
      at += b.tangent;
      if (b.latent) lo = std::min(lo, b.column), hi = std::max(hi, b.column + b.tangent - 1);
    }
    term_column_.resize(term.first_column + term.columns);
    if (hi >= lo) width_ = std::max(width_, hi - lo);
    term.first_latent = hi >= lo ? lo : latent_columns_;
    terms_.push_back(term);
  }
  // In band order: the evaluation threads' contiguous ranges then share the costly residuals
  // evenly (a problem adds its priors after its intervals) and each touches a stretch of the band.
  std::stable_sort(terms_.begin(), terms_.end(),
                   [](const Term& a, const Term& b) { return a.first_latent < b.first_latent; });
  return Status::Ok();
}

bool BandArrowProblem::Evaluate(ArrowSystem* system, int num_threads, double* cost) const {
  const size_t n = terms_.size();
  const int chunks = ChunkCount(n, num_threads, kMinChunk);
  parts_.resize(chunks);
  std::vector<double> costs(chunks, 0.0);
  std::vector<char> ok(chunks, 0);
  ParallelChunks(n, num_threads, kMinChunk, [&](int chunk, size_t begin, size_t end) {
    ArrowSystem* part = system ? (chunk == 0 ? system : &parts_[chunk]) : nullptr;
    if (part) part->Reset(globals_, latents(), width_);
    ok[chunk] = EvaluateRange(begin, end, part, &costs[chunk]);
  });
  *cost = 0.0;
  for (int c = 0; c < chunks; ++c) {
    if (!ok[c]) return false;
    *cost += costs[c];
    if (system && c > 0) system->Add(parts_[c]);
  }
  if (system) system->cost = *cost;
  return true;
}

bool BandArrowProblem::EvaluateRange(size_t begin, size_t end, ArrowSystem* system,
                                     double* cost) const {
  // Tangent Jacobian, column-major so that a column's m ≤ kMaxResiduals entries are contiguous.
  double jt[kMaxResiduals * kMaxColumns];
  double r[kMaxResiduals];
  double ambient[kMaxResiduals * kMaxColumns];
  double* jacobians[kMaxBlocks];
  // The manifolds' Jacobians, the same for every residual of this evaluation.
  const std::vector<RowMatrix> plus = system ? PlusJacobians() : std::vector<RowMatrix>();
  double sum = 0.0;  // Local: the threads' outputs share a cache line.
  for (size_t i = begin; i < end; ++i) {
    // The cost functions are scattered over the heap: fetch a later one's first lines now.
    if (i + kPrefetchAhead < end) {
      const char* ahead = reinterpret_cast<const char*>(terms_[i + kPrefetchAhead].cost);
      for (int line = 0; line < 4; ++line) __builtin_prefetch(ahead + 64 * line);
    }
    const Term& term = terms_[i];
    const int m = term.cost->num_residuals();
    const int* block = term_block_.data() + term.first_block;
    if (system) {
      int at = 0;
      for (int p = 0; p < term.num_blocks; ++p) {
        jacobians[p] = block[p] < 0 ? nullptr : ambient + at;
        if (block[p] >= 0) at += m * blocks_[block[p]].size;
      }
    }
    if (!term.cost->Evaluate(term_values_.data() + term.first_block, r,
                             system ? jacobians : nullptr)) {
      return false;
    }
    double s = 0.0;
    for (int k = 0; k < m; ++k) s += r[k] * r[k];
    double rho[3] = {s, 1.0, 0.0};
    if (term.loss) term.loss->Evaluate(s, rho);
    if (!std::isfinite(rho[0])) return false;
    sum += 0.5 * rho[0];
    if (system) AccumulateTerm(term, m, r, rho[1], jacobians, plus, jt, system);
  }
  *cost = sum;
  if (system) system->cost = sum;
  return true;
}

std::vector<RowMatrix> BandArrowProblem::PlusJacobians() const {
  std::vector<RowMatrix> plus(blocks_.size());
  for (size_t b = 0; b < blocks_.size(); ++b) {
    if (!blocks_[b].manifold) continue;
    plus[b].resize(blocks_[b].size, blocks_[b].tangent);
    blocks_[b].manifold->PlusJacobian(blocks_[b].values, plus[b].data());
  }
  return plus;
}

void BandArrowProblem::TangentJacobian(const Term& term, int m, double* const* jacobians,
                                       const std::vector<RowMatrix>& plus, double* jt) const {
  for (int p = 0; p < term.num_blocks; ++p) {
    const int index = term_block_[term.first_block + p];
    if (index < 0) continue;
    const Block& b = blocks_[index];
    const Eigen::Map<const RowMatrix> j(jacobians[p], m, b.size);
    Eigen::Map<Eigen::MatrixXd> out(jt + m * term_offset_[term.first_block + p], m, b.tangent);
    if (b.manifold) {
      out.noalias() = j * plus[index];
    } else {
      out = j;
    }
  }
}

void BandArrowProblem::AccumulateTerm(const Term& term, int m, const double* r, double weight,
                                      double* const* jacobians, const std::vector<RowMatrix>& plus,
                                      double* jt, ArrowSystem* system) const {
  TangentJacobian(term, m, jacobians, plus, jt);  // The globals' columns first.
  // Reweighted: H += ρ′JᵀJ, g += ρ′Jᵀr, entry by entry into the arrow's pieces.
  const int* column = term_column_.data() + term.first_column;
  const auto dot = [&](int a, const double* v) {
    double sum = 0.0;
    for (int k = 0; k < m; ++k) sum += jt[m * a + k] * v[k];
    return weight * sum;
  };
  for (int a = 0; a < term.columns; ++a) {
    (a < term.globals ? system->g_g : system->g_l)(column[a]) += dot(a, r);
  }
  for (int a = 0; a < term.globals; ++a) {
    for (int b = a; b < term.globals; ++b) {
      const double v = dot(a, jt + m * b);
      system->h_gg(column[a], column[b]) += v;
      if (b != a) system->h_gg(column[b], column[a]) += v;
    }
  }
  for (int a = term.globals; a < term.columns; ++a) {
    const int ca = column[a];
    for (int b = 0; b < term.globals; ++b) system->h_lg(ca, column[b]) += dot(a, jt + m * b);
    for (int b = term.globals; b < term.columns; ++b) {
      const int cb = column[b];
      if (cb >= ca) system->band(cb - ca, ca) += dot(a, jt + m * b);
    }
  }
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
  // [X | y] = H_ll⁻¹·[H_lg | g_l], one banded solve.
  RowMatrix xy(latents(), globals_ + 1);
  if (latents() > 0) {
    BandedLdlt ldlt;
    if (!ldlt.Compute(std::move(band))) return false;
    xy << system.h_lg, system.g_l;
    ldlt.SolveInPlace(&xy);
  }
  const auto x = xy.leftCols(globals_);
  const auto y = xy.col(globals_);
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
    const double* delta = (b.latent ? delta_l.data() : delta_g.data()) + b.column;
    if (b.manifold) {
      x.assign(b.values, b.values + b.size);
      b.manifold->Plus(x.data(), delta, b.values);
    } else {
      for (int i = 0; i < b.size; ++i) b.values[i] += delta[i];
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

}  // namespace band_arrow_internal
}  // namespace calib
