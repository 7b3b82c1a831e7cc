// LatentTimeProblem::Linearize: the Jacobian of the interval residuals, robustified as Ceres does,
// folded into the information blocks of the globals and of the time-ordered (banded) latents.
#include <calib/problems/laser/laser_latent_time_cost.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/timing/latent_time_problem.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace calib {

namespace {

// Intervals per thread, at least, and per batch of rows.
constexpr size_t kMinChunk = 1000, kBatch = 4096;

// One interval's residual and Jacobian as Ceres' Problem::Evaluate gives them with the loss
// applied: in tangent columns (a manifold's Plus Jacobian), with Triggs' correction of the
// robust loss (residual and Jacobian scaled by √ρ′, and a rank-one term where ρ″ > 0).
struct RobustRow {
  // An interval touches the six parameters, the clock (3) and at most two sample times and four
  // encoder times.
  static constexpr int kMaxEntries = 16;
  struct Entry {
    int column;
    double value[3];  // Per residual component.
  };
  double residual[3];
  double squared_norm = 0.0;  // Of the uncorrected residual.
  double cost = 0.0;          // ½ρ.
  std::array<Entry, kMaxEntries> entries;
  int num_entries = 0;
  // With `with_angles`: ∂r/∂(end angles) (3 × 4), corrected for the loss as the entries.
  bool has_angles = false;
  double angle[3][4];
};

// `column_of` gives a block's first tangent column (−1: constant); `manifold_block` is the one
// block with a manifold (the odometry's, 3 → 3), `plus` its Plus Jacobian.
template <typename ColumnOf>
bool EvaluateRobustRow(const ceres::CostFunction& function, double* const* blocks,
                       size_t num_blocks, const ColumnOf& column_of,
                       const ceres::LossFunction* loss, const double* manifold_block,
                       const Eigen::Matrix3d& plus, bool with_angles, RobustRow* row) {
  constexpr int kMaxAmbient = 3, kMaxBlocks = 12;
  const std::vector<int32_t>& sizes = function.parameter_block_sizes();
  if (num_blocks > static_cast<size_t>(kMaxBlocks)) return false;
  double storage[3 * kMaxAmbient * kMaxBlocks];
  double* jacobians[kMaxBlocks];
  for (size_t b = 0; b < num_blocks; ++b) {
    if (sizes[b] > kMaxAmbient) return false;
    jacobians[b] = column_of(blocks[b]) >= 0 ? storage + 3 * kMaxAmbient * b : nullptr;
  }
  double r[3];
  if (!function.Evaluate(blocks, r, jacobians)) return false;
  const double s = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
  double rho[3] = {s, 1.0, 0.0};
  if (loss) loss->Evaluate(s, rho);
  if (!std::isfinite(rho[0])) return false;
  row->squared_norm = s;
  row->cost = 0.5 * rho[0];
  const double sqrt_rho1 = std::sqrt(rho[1]);
  double residual_scale = sqrt_rho1, alpha_over_s = 0.0;
  if (s > 0.0 && rho[2] > 0.0) {
    const double alpha = 1.0 - std::sqrt(1.0 + 2.0 * s * rho[2] / rho[1]);
    residual_scale = sqrt_rho1 / (1.0 - alpha);
    alpha_over_s = alpha / s;
  }
  row->num_entries = 0;
  const Eigen::Map<const Eigen::Vector3d> rv(r);
  for (size_t b = 0; b < num_blocks; ++b) {
    if (!jacobians[b]) continue;
    const int size = sizes[b];
    if (row->num_entries + size > RobustRow::kMaxEntries) return false;
    // J ← √ρ′ (I − α r rᵀ/s) J, then to tangent columns.
    Eigen::Matrix<double, 3, kMaxAmbient> j = Eigen::Matrix<double, 3, kMaxAmbient>::Zero();
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < size; ++i) j(c, i) = jacobians[b][c * size + i];
    }
    j = (sqrt_rho1 * (j - alpha_over_s * rv * (rv.transpose() * j))).eval();
    if (blocks[b] == manifold_block) j = (j * plus).eval();
    const int first = column_of(blocks[b]);
    for (int t = 0; t < size; ++t) {
      row->entries[row->num_entries++] = {first + t, {j(0, t), j(1, t), j(2, t)}};
    }
  }
  for (int c = 0; c < 3; ++c) row->residual[c] = residual_scale * r[c];
  const auto* interval = dynamic_cast<const LaserLatentTimeCost*>(&function);
  row->has_angles = with_angles && interval != nullptr;
  if (row->has_angles) {
    double unused[3];
    Eigen::Matrix<double, 3, 4, Eigen::RowMajor> a;
    interval->EndAngleJacobian(blocks, unused, a.data());
    a = (sqrt_rho1 * (a - alpha_over_s * rv * (rv.transpose() * a))).eval();
    for (int c = 0; c < 3; ++c) {
      for (int w = 0; w < 4; ++w) row->angle[c][w] = a(c, w);
    }
  }
  return true;
}

// Adds one interval's row to the information blocks (per residual component for the latents).
void AddRow(const RobustRow& row, const ceres::LossFunction* loss, LatentLinearization* lin) {
  const int g = lin->num_globals;
  lin->data_cost += row.cost;
  lin->loss_sums.Add(row.squared_norm, loss, 3);
  const RobustRow::Entry* entries = row.entries.data();
  const int n = row.num_entries;
  for (int component = 0; component < 3; ++component) {
    const double r = row.residual[component];
    lin->rr_c(component) += r * r;
    Eigen::MatrixXd& band = lin->h_ll_band_c[component];
    for (int a = 0; a < n; ++a) {
      const int ca = entries[a].column;
      const double va = entries[a].value[component];
      if (ca < g) {
        for (int b = 0; b < n; ++b) {
          if (entries[b].column < g) {
            lin->h_gg(ca, entries[b].column) += va * entries[b].value[component];
          }
        }
        continue;
      }
      lin->b_l_c[component](ca - g) += va * r;
      for (int b = 0; b < n; ++b) {
        const int cb = entries[b].column;
        const double product = va * entries[b].value[component];
        if (cb < g) {
          lin->h_lg(ca - g, cb) += product;
        } else if (cb >= ca) {
          band(cb - ca, ca - g) += product;
        }
      }
    }
  }
}

// The row's gradient contribution Jᵀr (the loss applied: J′ᵀr′ = ρ′Jᵀr) into the interval's
// scores; a latent the scores have not met yet takes this row
// for its prior (`latent_row`).
void AddScores(const RobustRow& row, int g, int interval, LatentLinearization* lin) {
  auto& latents = lin->score_latents[interval];
  int used = 0;
  for (int a = 0; a < row.num_entries; ++a) {
    const RobustRow::Entry& e = row.entries[a];
    const double score =
        e.value[0] * row.residual[0] + e.value[1] * row.residual[1] + e.value[2] * row.residual[2];
    double angle[4] = {0.0, 0.0, 0.0, 0.0};
    for (int w = 0; row.has_angles && w < 4; ++w) {
      for (int c = 0; c < 3; ++c) angle[w] += e.value[c] * row.angle[c][w];
    }
    if (e.column < g) {
      lin->score_globals(interval, e.column) += score;
      for (int w = 0; w < 4; ++w) lin->angle_globals[w](interval, e.column) += angle[w];
      for (int c = 0; c < 3; ++c) lin->row_globals[c](interval, e.column) += e.value[c];
      continue;
    }
    const int latent = e.column - g;
    if (used < LatentLinearization::kMaxIntervalLatents) {
      latents[used] = {latent, score};
      std::copy(angle, angle + 4, latents[used].angle);
      std::copy(e.value, e.value + 3, latents[used++].row);
    }
    if (lin->latent_row[latent] < 0) lin->latent_row[latent] = interval;
  }
}

}  // namespace

StatusOr<LatentLinearization> LatentTimeProblem::Linearize(bool with_scores) const {
  LatentLinearization lin;
  lin.num_globals = 6;
  if (model_ == SensorClockModel::kFreeRunning) lin.num_globals += 3;  // t0, P, a.
  if (state_.sensor_sigma_s > 0.0 && estimate_offset_) lin.offset_global = lin.num_globals++;
  const std::vector<LatentTimeProblem::LatentRef> order = LatentOrder();
  const int num_latents = static_cast<int>(order.size());
  lin.latent_value.resize(num_latents);
  for (int i = 0; i < num_latents; ++i) {
    lin.latent_is_sensor.push_back(order[i].sensor);
    lin.latent_owner.push_back(order[i].owner);
    lin.latent_value(i) = *order[i].value;
  }

  const int g = lin.num_globals;
  // Column of each block of the intervals: the globals' first tangent column, the latents' own.
  std::vector<int> sensor_column(state_.sensor_latent.size(), -1);
  std::vector<int> encoder_column(state_.encoder_latent.size(), -1);
  for (int i = 0; i < num_latents; ++i) {
    (order[i].sensor ? sensor_column : encoder_column)[order[i].owner] = g + i;
  }
  const auto column_of = [&](const double* block) {
    if (block == odometry_) return 0;
    if (block == base_T_sensor_) return 3;
    if (block == clock_) return 6;
    if (block >= state_.sensor_latent.data() &&
        block < state_.sensor_latent.data() + state_.sensor_latent.size()) {
      return sensor_column[block - state_.sensor_latent.data()];
    }
    if (block >= state_.encoder_latent.data() &&
        block < state_.encoder_latent.data() + state_.encoder_latent.size()) {
      return encoder_column[block - state_.encoder_latent.data()];
    }
    return -1;
  };
  // The odometry's manifold (the only one): its Plus Jacobian is the same for every row.
  Eigen::Matrix3d plus = Eigen::Matrix3d::Identity();
  if (const ceres::Manifold* manifold = odometry_manifold_.get()) {
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> values;
    if (manifold->AmbientSize() != 3 || manifold->TangentSize() != 3 ||
        !manifold->PlusJacobian(odometry_, values.data())) {
      return Status::Internal("the timing-aware problem's odometry manifold is not 3 × 3");
    }
    plus = values;
  }
  // The band's width from the blocks alone (the rows are evaluated in batches below).
  int width = 0;
  for (size_t i = 0; i < interval_functions_.size(); ++i) {
    int lo = num_latents, hi = -1;
    for (int b = 0; b < NumIntervalBlocks(i); ++b) {
      const int column = column_of(IntervalBlocks(i)[b]);
      if (column >= g) lo = std::min(lo, column - g), hi = std::max(hi, column - g);
    }
    if (hi >= lo) width = std::max(width, hi - lo);
  }
  lin.h_gg = Eigen::MatrixXd::Zero(g, g);
  lin.h_lg = Eigen::MatrixXd::Zero(num_latents, g);
  lin.h_ll_band = Eigen::MatrixXd::Zero(width + 1, num_latents);
  lin.b_l = Eigen::VectorXd::Zero(num_latents);
  for (int c = 0; c < 3; ++c) {
    lin.h_ll_band_c[c] = Eigen::MatrixXd::Zero(width + 1, num_latents);
    lin.b_l_c[c] = Eigen::VectorXd::Zero(num_latents);
  }
  if (with_scores) {
    lin.score_globals = Eigen::MatrixXd::Zero(interval_functions_.size(), g);
    lin.score_latents.resize(interval_functions_.size());
    lin.latent_row.assign(num_latents, -1);
    for (Eigen::MatrixXd& a : lin.angle_globals)
      a = Eigen::MatrixXd::Zero(interval_functions_.size(), g);
    for (Eigen::MatrixXd& a : lin.row_globals)
      a = Eigen::MatrixXd::Zero(interval_functions_.size(), g);
    lin.interval_sample = data_.interval_start;
    lin.sample_angle = AngleSpreads();
  }
  // Rows evaluated in parallel a batch at a time (a buffer that stays in cache), added in order.
  std::vector<RobustRow> rows(std::min(interval_functions_.size(), kBatch));
  for (size_t first = 0; first < interval_functions_.size(); first += kBatch) {
    const size_t count = std::min(kBatch, interval_functions_.size() - first);
    std::vector<char> ok(ChunkCount(count, options_.num_threads, kMinChunk), 1);
    ParallelChunks(
        count, options_.num_threads, kMinChunk, [&](int chunk, size_t begin, size_t end) {
          // A local flag, stored once: the chunks' flags share a cache line.
          bool evaluated = true;
          for (size_t i = begin; i < end && evaluated; ++i) {
            evaluated =
                EvaluateRobustRow(*interval_functions_[first + i], IntervalBlocks(first + i),
                                  NumIntervalBlocks(first + i), column_of, loss_.get(), odometry_,
                                  plus, with_scores && !encoder_rates_.empty(), &rows[i]);
          }
          ok[chunk] = evaluated;
        });
    if (std::find(ok.begin(), ok.end(), 0) != ok.end()) {
      return Status::Internal("the timing-aware problem could not be evaluated");
    }
    for (size_t i = 0; i < count; ++i) {
      AddRow(rows[i], loss_.get(), &lin);
      if (with_scores) {
        AddScores(rows[i], g, static_cast<int>(first + i), &lin);
      }
    }
  }
  if (model_ == SensorClockModel::kFreeRunning) {
    lin.h_gg(8, 8) += 1.0 / (kClockDriftSigmaS * kClockDriftSigmaS);  // The curvature's prior.
    if (state_.period_prior_sigma_s > 0.0) {
      lin.h_gg(7, 7) += 1.0 / (state_.period_prior_sigma_s * state_.period_prior_sigma_s);
    }
    if (state_.sensor_sigma_s > 0.0) {
      // The stamp prior: gradient (1, n, u², −1)/σ_s in (t0, P, a, τ).
      const double w = 1.0 / state_.sensor_sigma_s;
      std::vector<int> sample_row(data_.samples.size(), -1);  // An interval at the sample.
      for (size_t i = 0; i < data_.interval_start.size(); ++i) {
        for (const int k : {data_.interval_start[i], data_.interval_start[i] + 1}) {
          if (sample_row[k] < 0) sample_row[k] = static_cast<int>(i);
        }
      }
      for (const int k : ClockSamples()) {
        const double n = state_.clock_index[k];
        Eigen::Vector4d g(w, w * n, w * state_.clock.Curvature(n), -w);
        const double r = (SampleTime(k) - data_.samples[k].stamp_s - offset_) * w;
        lin.stamp_prior_chi2 += r * r;
        ++lin.stamp_prior_count;
        if (lin.offset_global < 0) g(3) = 0.0;
        const int index[4] = {6, 7, 8, lin.offset_global};
        for (int a = 0; with_scores && a < 4; ++a) {
          if (index[a] >= 0) lin.score_globals(sample_row[k], index[a]) += g(a) * r;
        }
        for (int a = 0; a < 4; ++a) {
          for (int b = 0; b < 4; ++b) {
            if (index[a] >= 0 && index[b] >= 0) lin.h_gg(index[a], index[b]) += g(a) * g(b);
          }
        }
      }
    }
  }
  for (int c = 0; c < 3; ++c) {
    lin.h_ll_band += lin.h_ll_band_c[c];
    lin.b_l += lin.b_l_c[c];
  }
  lin.noise_sigma = state_.noise_sigma;
  lin.num_intervals = static_cast<int>(interval_functions_.size());
  for (int i = 0; i < 3; ++i) lin.odometry_plus_jacobian(i, i) = odometry_[i];
  return lin;
}

}  // namespace calib
