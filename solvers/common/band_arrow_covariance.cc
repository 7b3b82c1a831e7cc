// The covariance side of BandArrowProblem. With H = [A B; Bᵀ C] (A the banded latent block),
// X = A⁻¹B and S = C − BᵀX the Schur complement of the latents:
//   Σ_gg = S⁻¹,  Σ_lg = −X·S⁻¹,  Σ_ll = A⁻¹ + X·S⁻¹·Xᵀ,
// where a residual's leverage needs A⁻¹ only inside the band (Takahashi's recurrences, O(n·w²))
// and a few requested latent blocks need a few columns of A⁻¹: linear in n throughout, where a
// general sparse covariance pays for every column it is asked for.
#include <calib/solvers/common/band_arrow_covariance.h>
#include <calib/solvers/common/band_arrow_problem.h>
#include <calib/solvers/common/parallel_chunks.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace calib {
namespace band_arrow_internal {
namespace {

// The smallest pivot of the Schur complement scaled to a unit diagonal that still counts as
// information (ceres::Covariance's default reciprocal condition number).
constexpr double kMinPivot = 1e-14;

bool PositiveDefinite(const Eigen::MatrixXd& s) {
  const Eigen::VectorXd d = s.diagonal();
  if (!(d.array() > 0.0).all()) return false;
  const Eigen::VectorXd scale = d.cwiseSqrt().cwiseInverse();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(scale.asDiagonal() * s * scale.asDiagonal());
  return ldlt.info() == Eigen::Success && (ldlt.vectorD().array() > kMinPivot).all();
}

}  // namespace

template <typename Sigma>
bool BandArrowProblem::TermLeverages(size_t begin, size_t end, const std::vector<RowMatrix>& plus,
                                     const Sigma& sigma, std::vector<double>* leverages) const {
  double jt[kMaxResiduals * kMaxColumns], r[kMaxResiduals];
  double ambient[kMaxResiduals * kMaxColumns];
  double* jacobians[kMaxBlocks];
  for (size_t i = begin; i < end; ++i) {
    const Term& term = terms_[i];
    const int m = term.cost->num_residuals();
    const int* block = term_block_.data() + term.first_block;
    int at = 0;
    for (int p = 0; p < term.num_blocks; ++p) {
      jacobians[p] = block[p] < 0 ? nullptr : ambient + at;
      if (block[p] >= 0) at += m * blocks_[block[p]].size;
    }
    if (!term.cost->Evaluate(term_values_.data() + term.first_block, r, jacobians)) return false;
    double s = 0.0;
    for (int k = 0; k < m; ++k) s += r[k] * r[k];
    double rho[3] = {s, 1.0, 0.0};
    if (term.loss) term.loss->Evaluate(s, rho);
    TangentJacobian(term, m, jacobians, plus, jt);
    // tr(J·Σ·Jᵀ) = Σ_ab Σ(a, b)·(column a · column b).
    double trace = 0.0;
    for (int a = 0; a < term.columns; ++a) {
      for (int b = a; b < term.columns; ++b) {
        double dot = 0.0;
        for (int k = 0; k < m; ++k) dot += jt[m * a + k] * jt[m * b + k];
        trace += (a == b ? 1.0 : 2.0) * sigma(term, a, b) * dot;
      }
    }
    (*leverages)[term.index] = rho[1] * trace;
  }
  return true;
}

Status BandArrowProblem::Covariance(const std::vector<const double*>& blocks,
                                    const std::vector<int>& sizes, int num_threads,
                                    Eigen::MatrixXd* covariance,
                                    std::vector<double>* leverages) const {
  const Status singular = Status::NotObservable("the information matrix is singular");
  ArrowSystem system;
  double cost = 0.0;
  if (!Evaluate(&system, num_threads, &cost)) {
    return Status::Internal("a residual could not be evaluated for the covariance");
  }
  const int n = latents(), g = globals_;
  BandedLdlt ldlt;
  RowMatrix x = system.h_lg;  // X = A⁻¹B.
  if (n > 0) {
    if (!ldlt.Compute(system.band)) return singular;
    ldlt.SolveInPlace(&x);
  }
  Eigen::MatrixXd s_inverse = Eigen::MatrixXd::Zero(g, g);
  if (g > 0) {
    const Eigen::MatrixXd s = system.h_gg - system.h_lg.transpose() * x;
    if (!PositiveDefinite(s)) return singular;
    s_inverse = s.ldlt().solve(Eigen::MatrixXd::Identity(g, g));
  }
  const RowMatrix xs = x * s_inverse;  // −Σ_lg.
  const std::vector<RowMatrix> plus = PlusJacobians();

  // The requested blocks: their tangent columns (−1: constant), then A⁻¹'s columns for latents.
  std::vector<int> first(blocks.size(), -1), tangent(blocks.size(), 0);
  std::vector<int> latent_at;  // Per requested latent column, its index among the latents.
  int columns = 0;
  for (size_t k = 0; k < blocks.size(); ++k) {
    const auto it = block_index_.find(blocks[k]);
    if (it == block_index_.end()) continue;
    first[k] = columns;
    tangent[k] = blocks_[it->second].tangent;
    columns += tangent[k];
  }
  std::vector<int> column(columns);
  std::vector<bool> latent(columns, false);
  for (size_t k = 0; k < blocks.size(); ++k) {
    if (first[k] < 0) continue;
    const Block& b = blocks_[block_index_.at(blocks[k])];
    for (int c = 0; c < b.tangent; ++c) {
      column[first[k] + c] = b.column + c;
      latent[first[k] + c] = b.latent;
      if (b.latent) latent_at.push_back(first[k] + c);
    }
  }
  RowMatrix a_inverse = RowMatrix::Zero(n, latent_at.size());
  for (size_t c = 0; c < latent_at.size(); ++c) a_inverse(column[latent_at[c]], c) = 1.0;
  if (!latent_at.empty()) ldlt.SolveInPlace(&a_inverse);
  Eigen::MatrixXd tangent_cov(columns, columns);
  for (int a = 0; a < columns; ++a) {
    for (int b = 0; b < columns; ++b) {
      const int ca = column[a], cb = column[b];
      if (!latent[a] && !latent[b]) {
        tangent_cov(a, b) = s_inverse(ca, cb);
      } else if (latent[a] != latent[b]) {
        tangent_cov(a, b) = latent[a] ? -xs(ca, cb) : -xs(cb, ca);
      } else {
        const int nb =
            static_cast<int>(std::find(latent_at.begin(), latent_at.end(), b) - latent_at.begin());
        tangent_cov(a, b) = a_inverse(ca, nb) + xs.row(ca).dot(x.row(cb));
      }
    }
  }
  // Ambient: P·Σ·Pᵀ with P the Plus Jacobian of each block's manifold (zeros for constants).
  std::vector<int> ambient_first(blocks.size() + 1, 0);
  for (size_t k = 0; k < blocks.size(); ++k) ambient_first[k + 1] = ambient_first[k] + sizes[k];
  covariance->setZero(ambient_first.back(), ambient_first.back());
  const auto lift = [&](size_t k) {
    const Block& b = blocks_[block_index_.at(blocks[k])];
    const int index = block_index_.at(blocks[k]);
    return b.manifold ? Eigen::MatrixXd(plus[index]) : Eigen::MatrixXd::Identity(b.size, b.size);
  };
  for (size_t a = 0; a < blocks.size(); ++a) {
    if (first[a] < 0) continue;
    const Eigen::MatrixXd pa = lift(a);
    for (size_t b = 0; b < blocks.size(); ++b) {
      if (first[b] < 0) continue;
      covariance->block(ambient_first[a], ambient_first[b], sizes[a], sizes[b]) =
          pa * tangent_cov.block(first[a], first[b], tangent[a], tangent[b]) * lift(b).transpose();
    }
  }
  if (leverages == nullptr) return Status::Ok();

  // Σ between two columns of a term: A⁻¹ inside the band from Takahashi's recurrences.
  const Eigen::MatrixXd band_inverse = n > 0 ? ldlt.InverseBand() : Eigen::MatrixXd();
  const auto sigma = [&](const Term& term, int a, int b) {
    const int* col = term_column_.data() + term.first_column;
    const int ca = col[a], cb = col[b];
    const bool la = a >= term.globals, lb = b >= term.globals;
    if (!la && !lb) return s_inverse(ca, cb);
    if (la != lb) return la ? -xs(ca, cb) : -xs(cb, ca);
    const int lo = std::min(ca, cb), d = std::abs(ca - cb);
    return band_inverse(d, lo) + xs.row(ca).dot(x.row(cb));
  };
  leverages->assign(terms_.size(), 0.0);
  std::vector<char> ok(ChunkCount(terms_.size(), num_threads, kMinChunk), 0);
  ParallelChunks(terms_.size(), num_threads, kMinChunk, [&](int chunk, size_t begin, size_t end) {
    ok[chunk] = TermLeverages(begin, end, plus, sigma, leverages);
  });
  if (std::find(ok.begin(), ok.end(), 0) != ok.end()) {
    return Status::Internal("a residual could not be evaluated for its leverage");
  }
  return Status::Ok();
}

}  // namespace band_arrow_internal
}  // namespace calib

namespace calib {

StatusOr<BandArrowCovariance> ComputeBandArrowCovariance(const std::vector<double*>& latents,
                                                         const std::vector<const double*>& blocks,
                                                         bool with_leverages, int num_threads,
                                                         ceres::Problem* problem) {
  band_arrow_internal::BandArrowProblem arrow;
  CALIB_RETURN_IF_ERROR(arrow.Build(latents, problem));
  std::vector<int> sizes;
  for (const double* block : blocks) sizes.push_back(problem->ParameterBlockSize(block));
  BandArrowCovariance out;
  CALIB_RETURN_IF_ERROR(arrow.Covariance(blocks, sizes, num_threads, &out.blocks,
                                         with_leverages ? &out.leverages : nullptr));
  return out;
}

}  // namespace calib
