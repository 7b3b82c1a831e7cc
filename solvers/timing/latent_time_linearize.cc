// LatentTimeProblem::Linearize: the Jacobian of the interval residuals from Ceres, folded into the
// information blocks of the globals and of the time-ordered (banded) latents.
#include <calib/solvers/timing/latent_time_problem.h>

#include <algorithm>

namespace calib {

StatusOr<LatentLinearization> LatentTimeProblem::Linearize() const {
  LatentLinearization lin;
  std::vector<double*> blocks = {const_cast<double*>(odometry_),
                                 const_cast<double*>(base_T_sensor_)};
  lin.num_globals = 6;
  if (model_ == SensorClockModel::kFreeRunning) {
    blocks.push_back(const_cast<double*>(clock_));
    lin.num_globals += 3;
    if (state_.sensor_sigma_s > 0.0 && estimate_offset_) {
      blocks.push_back(const_cast<double*>(&offset_));
      lin.offset_global = lin.num_globals++;
    }
  } else if (state_.sensor_sigma_s > 0.0 && estimate_offset_) {
    blocks.push_back(const_cast<double*>(&offset_));
    lin.offset_global = lin.num_globals++;
  }
  const std::vector<LatentTimeProblem::LatentRef> order = LatentOrder();
  const int num_latents = static_cast<int>(order.size());
  lin.latent_value.resize(num_latents);
  for (int i = 0; i < num_latents; ++i) {
    lin.latent_is_sensor.push_back(order[i].sensor);
    lin.latent_owner.push_back(order[i].owner);
    lin.latent_value(i) = *order[i].value;
    blocks.push_back(order[i].value);
  }

  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = blocks;
  evaluate.residual_blocks = interval_costs_;
  evaluate.apply_loss_function = true;
  evaluate.num_threads = options_.num_threads;
  double cost = 0.0;
  std::vector<double> residuals;
  ceres::CRSMatrix jacobian;
  if (!problem_->Evaluate(evaluate, &cost, &residuals, nullptr, &jacobian)) {
    return Status::Internal("the timing-aware problem could not be evaluated");
  }
  lin.data_cost = cost;
  const int g = lin.num_globals;
  // Half-bandwidth of the latent block: the widest latent span of one residual row.
  int width = 0;
  for (int row = 0; row < jacobian.num_rows; ++row) {
    int lo = num_latents, hi = -1;
    for (int e = jacobian.rows[row]; e < jacobian.rows[row + 1]; ++e) {
      const int c = jacobian.cols[e] - g;
      if (c >= 0) lo = std::min(lo, c), hi = std::max(hi, c);
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
  // Rows come three per interval, in the residual's (x, y, θ) order.
  for (int row = 0; row < jacobian.num_rows; ++row) {
    const int component = row % 3;
    lin.rr_c(component) += residuals[row] * residuals[row];
    const int begin = jacobian.rows[row], end = jacobian.rows[row + 1];
    for (int a = begin; a < end; ++a) {
      const int ca = jacobian.cols[a];
      const double va = jacobian.values[a];
      if (ca >= g) lin.b_l_c[component](ca - g) += va * residuals[row];
      for (int b = begin; b < end; ++b) {
        const int cb = jacobian.cols[b];
        const double product = va * jacobian.values[b];
        if (ca < g && cb < g) {
          lin.h_gg(ca, cb) += product;
        } else if (ca >= g && cb < g) {
          lin.h_lg(ca - g, cb) += product;
        } else if (ca >= g && cb >= ca) {
          lin.h_ll_band_c[component](cb - ca, ca - g) += product;
        }
      }
    }
  }
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
  for (const ceres::ResidualBlockId id : interval_costs_) {
    Eigen::Vector3d r;
    double block_cost = 0.0;
    problem_->EvaluateResidualBlock(id, false, &block_cost, r.data(), nullptr);
    lin.loss_sums.Add(r.squaredNorm(), loss_.get(), 3);
  }
  return lin;
}

}  // namespace calib
