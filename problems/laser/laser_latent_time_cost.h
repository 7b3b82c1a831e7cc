#ifndef CALIB_PROBLEMS_LASER_LASER_LATENT_TIME_COST_H_
#define CALIB_PROBLEMS_LASER_LASER_LATENT_TIME_COST_H_

#include <calib/core/timing/wheel_angle_spline.h>
#include <calib/problems/laser/laser_latent_time_residual.h>
#include <ceres/cost_function.h>
#include <ceres/jet.h>

#include <algorithm>
#include <vector>

namespace calib {

// LaserLatentTimeResidual with its time chain differentiated by hand: automatic differentiation
// runs once, on the ten inputs r(o, ℓ, α) really has (odometry, mounting, the four end angles), and
// each end angle α(t; e_j, e_{j+1}) passes on to its time blocks ∂α/∂t, ∂α/∂e_j, ∂α/∂e_{j+1}
// (HermiteWheelAnglePartials), with t = stamp + δ (∂t/∂δ = 1) or t0 + P·n + a·u² (∂t/∂(t0, P, a) =
// (1, n, u²)). Dynamic automatic differentiation over every block instead takes two passes of
// eight-wide jets, and this residual is the timing-aware solve's main cost.
class LaserLatentTimeCost : public ceres::CostFunction {
 public:
  LaserLatentTimeCost(LaserLatentTimeResidual residual, const std::vector<int>& block_sizes)
      : residual_(std::move(residual)) {
    *mutable_parameter_block_sizes() = block_sizes;
    set_num_residuals(3);
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    double ends[4];
    EndPartials partials[2];
    Ends(residual_.start(), parameters, &ends[0], &partials[0]);
    Ends(residual_.end(), parameters, &ends[2], &partials[1]);
    if (jacobians == nullptr) {
      residual_.FromEndAngles(parameters[0], parameters[1], ends, residuals);
      return true;
    }
    using Jet = ceres::Jet<double, 10>;
    Jet odometry[3], mounting[3], jet_ends[4], r[3];
    for (int i = 0; i < 3; ++i) {
      odometry[i] = Jet(parameters[0][i], i);
      mounting[i] = Jet(parameters[1][i], 3 + i);
    }
    for (int i = 0; i < 4; ++i) jet_ends[i] = Jet(ends[i], 6 + i);
    residual_.FromEndAngles(odometry, mounting, jet_ends, r);
    for (int c = 0; c < 3; ++c) residuals[c] = r[c].a;
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    for (size_t b = 0; b < sizes.size(); ++b) {
      if (jacobians[b]) std::fill(jacobians[b], jacobians[b] + 3 * sizes[b], 0.0);
    }
    for (int b = 0; b < 2; ++b) {
      if (!jacobians[b]) continue;
      for (int c = 0; c < 3; ++c) {
        for (int i = 0; i < 3; ++i) jacobians[b][c * 3 + i] = r[c].v(3 * b + i);
      }
    }
    for (int e = 0; e < 2; ++e) {
      const LatentTimeEnd& end = e == 0 ? residual_.start() : residual_.end();
      // d r/d t of this end, through its left and right angles.
      double dr_dt[3], dr_de[2][3];
      for (int c = 0; c < 3; ++c) {
        const double dl = r[c].v(6 + 2 * e), dright = r[c].v(7 + 2 * e);
        dr_dt[c] = dl * partials[e].t[0] + dright * partials[e].t[1];
        for (int j = 0; j < 2; ++j) {
          dr_de[j][c] = dl * partials[e].e[j][0] + dright * partials[e].e[j][1];
        }
      }
      if (end.time_block >= 0 && jacobians[end.time_block]) {
        double* jac = jacobians[end.time_block];
        if (end.clock) {
          const double g[3] = {1.0, end.index, end.curvature};
          for (int c = 0; c < 3; ++c) {
            for (int i = 0; i < 3; ++i) jac[c * 3 + i] += dr_dt[c] * g[i];
          }
        } else {
          for (int c = 0; c < 3; ++c) jac[c] += dr_dt[c];
        }
      }
      for (int j = 0; j < 2; ++j) {
        const int block = end.encoder_block[j];
        if (block < 0 || !jacobians[block]) continue;
        for (int c = 0; c < 3; ++c) jacobians[block][c] += dr_de[j][c];
      }
    }
    return true;
  }

  // The residual and its derivatives by the four end angles (start left, start right, end left,
  // end right; 3 × 4, row-major): how an error of the wheel angles between polls moves it.
  void EndAngleJacobian(double const* const* parameters, double* residuals,
                        double* jacobian) const {
    using Jet = ceres::Jet<double, 4>;
    double ends[4];
    LaserLatentTimeResidual::AnglesAt(residual_.start(), parameters, &ends[0], &ends[1]);
    LaserLatentTimeResidual::AnglesAt(residual_.end(), parameters, &ends[2], &ends[3]);
    Jet odometry[3], mounting[3], jet_ends[4], r[3];
    for (int i = 0; i < 3; ++i) {
      odometry[i] = Jet(parameters[0][i]);
      mounting[i] = Jet(parameters[1][i]);
    }
    for (int i = 0; i < 4; ++i) jet_ends[i] = Jet(ends[i], i);
    residual_.FromEndAngles(odometry, mounting, jet_ends, r);
    for (int c = 0; c < 3; ++c) {
      residuals[c] = r[c].a;
      for (int i = 0; i < 4; ++i) jacobian[4 * c + i] = r[c].v(i);
    }
  }

  static ceres::CostFunction* Create(const Pose2d& sensor_motion,
                                     const Eigen::Matrix3d* sqrt_information,
                                     const LatentTimeEnd& start, const LatentTimeEnd& end,
                                     std::vector<double> interior_left_rad,
                                     std::vector<double> interior_right_rad,
                                     const std::vector<int>& block_sizes) {
    return new LaserLatentTimeCost(
        LaserLatentTimeResidual(sensor_motion, sqrt_information, start, end,
                                std::move(interior_left_rad), std::move(interior_right_rad)),
        block_sizes);
  }

 private:
  // ∂(left, right)/∂t and ∂(left, right)/∂e_j, j = 0, 1.
  struct EndPartials {
    double t[2];
    double e[2][2];
  };

  static void Ends(const LatentTimeEnd& end, double const* const* parameters, double* angles,
                   EndPartials* partials) {
    LaserLatentTimeResidual::AnglesAt(end, parameters, &angles[0], &angles[1]);
    double e[2];
    for (int i = 0; i < 2; ++i) {
      e[i] = end.encoder_stamp_s[i];
      if (end.encoder_block[i] >= 0) e[i] += parameters[end.encoder_block[i]][0];
    }
    const double t = LaserLatentTimeResidual::Time(end, parameters);
    const HermitePartials left = HermiteWheelAnglePartials(
        t, e[0], e[1], end.left_rad[0], end.left_rad[1], end.left_rate[0], end.left_rate[1]);
    const HermitePartials right = HermiteWheelAnglePartials(
        t, e[0], e[1], end.right_rad[0], end.right_rad[1], end.right_rate[0], end.right_rate[1]);
    *partials = EndPartials{{left.t, right.t}, {{left.e0, right.e0}, {left.e1, right.e1}}};
  }

  LaserLatentTimeResidual residual_;
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_LASER_LASER_LATENT_TIME_COST_H_
