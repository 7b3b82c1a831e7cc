// LatentTimeProblem::Linearize: the Jacobian of the interval residuals, robustified as Ceres does,
// folded into the information blocks of the globals and of the time-ordered (banded) latents.
#include <calib/solvers/timing/latent_time_problem.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

namespace calib {

namespace {

// One interval's residual and Jacobian as Ceres' Problem::Evaluate gives them with the loss
// applied: in tangent columns (a manifold's Plus Jacobian), with Triggs' correction of the
// robust loss (residual and Jacobian scaled by √ρ′, and a rank-one term where ρ″ > 0).
struct RobustRow {
  struct Entry {
    int column;
    double value[3];  // Per residual component.
  };
  double residual[3];
  double squared_norm = 0.0;  // Of the uncorrected residual.
  double cost = 0.0;          // ½ρ.
  std::vector<Entry> entries;
};

template <typename ColumnOf>
bool EvaluateRobustRow(const ceres::CostFunction& function, const std::vector<double*>& blocks,
                       const ColumnOf& column_of, const ceres::LossFunction* loss,
                       const ceres::Problem& problem, RobustRow* row) {
  constexpr int kMaxAmbient = 3;
  const std::vector<int32_t>& sizes = function.parameter_block_sizes();
  std::vector<double> storage(3 * kMaxAmbient * blocks.size(), 0.0);
  std::vector<double*> jacobians(blocks.size(), nullptr);
  for (size_t b = 0; b < blocks.size(); ++b) {
    if (sizes[b] > kMaxAmbient) return false;
    if (column_of(blocks[b]) >= 0) jacobians[b] = storage.data() + 3 * kMaxAmbient * b;
  }
  double r[3];
  if (!function.Evaluate(blocks.data(), r, jacobians.data())) return false;
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
  row->entries.clear();
  for (size_t b = 0; b < blocks.size(); ++b) {
    if (!jacobians[b]) continue;
    const int size = sizes[b];
    // J ← √ρ′ (I − α r rᵀ/s) J, then to tangent columns.
    Eigen::Matrix<double, 3, kMaxAmbient> j = Eigen::Matrix<double, 3, kMaxAmbient>::Zero();
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < size; ++i) j(c, i) = jacobians[b][c * size + i];
    }
    const Eigen::Map<const Eigen::Vector3d> rv(r);
    j = (sqrt_rho1 * (j - alpha_over_s * rv * (rv.transpose() * j))).eval();
    int tangent = size;
    if (const ceres::Manifold* manifold = problem.GetManifold(blocks[b])) {
      tangent = manifold->TangentSize();
      Eigen::Matrix<double, kMaxAmbient, kMaxAmbient, Eigen::RowMajor> plus =
          Eigen::Matrix<double, kMaxAmbient, kMaxAmbient, Eigen::RowMajor>::Zero();
      double plus_values[kMaxAmbient * kMaxAmbient];
      if (tangent > kMaxAmbient || !manifold->PlusJacobian(blocks[b], plus_values)) return false;
      for (int i = 0; i < size; ++i) {
        for (int t = 0; t < tangent; ++t) plus(i, t) = plus_values[i * tangent + t];
      }
      j = (j * plus).eval();
    }
    const int first = column_of(blocks[b]);
    for (int t = 0; t < tangent; ++t) {
      row->entries.push_back({first + t, {j(0, t), j(1, t), j(2, t)}});
    }
  }
  for (int c = 0; c < 3; ++c) row->residual[c] = residual_scale * r[c];
  return true;
}

// Adds one interval's row to the information blocks (per residual component for the latents).
void AddRow(const RobustRow& row, const ceres::LossFunction* loss, LatentLinearization* lin) {
  const int g = lin->num_globals;
  lin->data_cost += row.cost;
  lin->loss_sums.Add(row.squared_norm, loss, 3);
  for (int component = 0; component < 3; ++component) {
    const double r = row.residual[component];
    lin->rr_c(component) += r * r;
    for (const RobustRow::Entry& a : row.entries) {
      const int ca = a.column;
      const double va = a.value[component];
      if (ca >= g) lin->b_l_c[component](ca - g) += va * r;
      for (const RobustRow::Entry& b : row.entries) {
        const int cb = b.column;
        const double product = va * b.value[component];
        if (ca < g && cb < g) {
          lin->h_gg(ca, cb) += product;
        } else if (ca >= g && cb < g) {
          lin->h_lg(ca - g, cb) += product;
        } else if (ca >= g && cb >= ca) {
          lin->h_ll_band_c[component](cb - ca, ca - g) += product;
        }
      }
    }
  }
}

}  // namespace

StatusOr<LatentLinearization> LatentTimeProblem::Linearize() const {
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
  std::vector<RobustRow> rows(interval_costs_.size());
  int width = 0;
  for (size_t i = 0; i < interval_costs_.size(); ++i) {
    if (!EvaluateRobustRow(*interval_functions_[i], interval_blocks_[i], column_of, loss_.get(),
                           *problem_, &rows[i])) {
      return Status::Internal("the timing-aware problem could not be evaluated");
    }
    int lo = num_latents, hi = -1;
    for (const RobustRow::Entry& e : rows[i].entries) {
      if (e.column >= g) lo = std::min(lo, e.column - g), hi = std::max(hi, e.column - g);
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
  for (const RobustRow& row : rows) AddRow(row, loss_.get(), &lin);
  if (model_ == SensorClockModel::kFreeRunning) {
    lin.h_gg(8, 8) += 1.0 / (kClockDriftSigmaS * kClockDriftSigmaS);  // The curvature's prior.
    if (state_.sensor_sigma_s > 0.0) {
      // The stamp prior: gradient (1, n, u², −1)/σ_s in (t0, P, a, τ).
      const double w = 1.0 / state_.sensor_sigma_s;
      for (const int k : ClockSamples()) {
        const double n = state_.clock_index[k];
        Eigen::Vector4d g(w, w * n, w * state_.clock.Curvature(n), -w);
        const double r = (SampleTime(k) - data_.samples[k].stamp_s - offset_) * w;
        lin.stamp_prior_chi2 += r * r;
        ++lin.stamp_prior_count;
        if (lin.offset_global < 0) g(3) = 0.0;
        const int index[4] = {6, 7, 8, lin.offset_global};
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
  lin.num_intervals = static_cast<int>(interval_costs_.size());
  for (int i = 0; i < 3; ++i) lin.odometry_plus_jacobian(i, i) = odometry_[i];
  return lin;
}

}  // namespace calib
