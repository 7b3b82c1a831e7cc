#ifndef CALIB_PROBLEMS_SCAN_SCAN_PAIR_RESIDUAL_H_
#define CALIB_PROBLEMS_SCAN_SCAN_PAIR_RESIDUAL_H_

#include <calib/core/diff_drive.h>
#include <calib/core/se2.h>
#include <ceres/dynamic_autodiff_cost_function.h>

#include <Eigen/Core>
#include <vector>

namespace calib {

// Two scans of one pair, their beams placed through the odometry: every beam's point p_k (in the
// laser frame at the beam's own time t_k, shifted by the sensor's time offset δ) goes to the base
// frame at the timeline's start t₀,
//   x_k = o(t₀ → t_k + δ; r_l, r_r, b) ∘ ℓ ∘ p_k,
// o the wheel arcs between the encoder knots from t₀ (the last one cut at t_k + δ, the wheels
// turning at that step's constant speed), ℓ = base_T_laser. (δ also moves t₀, but that moves
// every point of the pair rigidly, which no point-to-line distance sees.)
struct ScanPairGeometry {
  std::vector<WheelStep> steps;   // The wheels' turns between consecutive knots from t₀ on.
  double located_offset_s = 0.0;  // The δ at which each beam's step was located.
  struct Beam {
    int step = 0;  // The knot interval t_k + δ falls in (steps.size(): the last knot).
    // Of that step's turns done at t_k + located_offset_s, and d(fraction)/dδ.
    double fraction = 0.0;
    double fraction_per_s = 0.0;
    Eigen::Vector2d point_m = Eigen::Vector2d::Zero();  // p_k.
  };
  std::vector<Beam> beams;  // Every beam a line uses.
  // A current beam pulled onto the line through two reference beams, with its whitening weight.
  struct Line {
    int current = 0, a = 0, b = 0;  // Indices into beams.
    double weight = 1.0;
  };
  std::vector<Line> lines;
};

// Every beam's x_k for the given parameters (the residual's first half, shared with the
// correspondence search).
template <typename T>
void PlaceBeams(const ScanPairGeometry& g, const T* odometry, const T* base_T_laser,
                const T& time_offset_s, std::vector<Eigen::Matrix<T, 2, 1>>* out) {
  using std::cos;
  using std::sin;
  std::vector<Pose2<T>> knots(g.steps.size() + 1);
  knots[0] = Pose2<T>::Zero();
  for (size_t s = 0; s < g.steps.size(); ++s) {
    knots[s + 1] =
        Compose(knots[s], WheelStepDisplacement(odometry[0], odometry[1], odometry[2],
                                                T(g.steps[s].left_rad), T(g.steps[s].right_rad)));
  }
  const Pose2<T> mounting(base_T_laser[0], base_T_laser[1], base_T_laser[2]);
  const T shift_s = time_offset_s - T(g.located_offset_s);
  out->resize(g.beams.size());
  for (size_t k = 0; k < g.beams.size(); ++k) {
    const ScanPairGeometry::Beam& beam = g.beams[k];
    Pose2<T> base = knots[beam.step];
    if (beam.step < static_cast<int>(g.steps.size())) {
      const WheelStep& step = g.steps[beam.step];
      const T fraction = T(beam.fraction) + T(beam.fraction_per_s) * shift_s;
      base =
          Compose(base, WheelStepDisplacement(odometry[0], odometry[1], odometry[2],
                                              fraction * step.left_rad, fraction * step.right_rad));
    }
    const Pose2<T> laser = Compose(base, mounting);
    const T c = cos(laser(2));
    const T s = sin(laser(2));
    (*out)[k] = Eigen::Matrix<T, 2, 1>(laser(0) + c * beam.point_m.x() - s * beam.point_m.y(),
                                       laser(1) + s * beam.point_m.x() + c * beam.point_m.y());
  }
}

// The point-to-line distances of one scan pair (Censi's PL-ICP metric with the sensor poses from
// the odometry instead of a matcher): for a line (c; a, b),
//   r = w · n̂(x_b − x_a) · (x_c − x_a),   n̂(d) = (−d_y, d_x)/‖d‖,
// w = 1/(σ·√v) whitening the range noise σ of its three points (v from their beam directions),
// times a robust weight. Parameter blocks: odometry = (r_l, r_r, b), base_T_laser = (x, y, θ),
// time offset δ (s).
// The geometry is held by pointer and must outlive the cost function.
class ScanPairResidual {
 public:
  explicit ScanPairResidual(const ScanPairGeometry* geometry) : geometry_(geometry) {}

  template <typename T>
  bool operator()(T const* const* parameters, T* residuals) const {
    using std::sqrt;
    std::vector<Eigen::Matrix<T, 2, 1>> x;
    PlaceBeams(*geometry_, parameters[0], parameters[1], parameters[2][0], &x);
    for (size_t i = 0; i < geometry_->lines.size(); ++i) {
      const ScanPairGeometry::Line& line = geometry_->lines[i];
      const Eigen::Matrix<T, 2, 1> d = x[line.b] - x[line.a];
      const Eigen::Matrix<T, 2, 1> e = x[line.current] - x[line.a];
      residuals[i] = T(line.weight) * (d.x() * e.y() - d.y() * e.x()) / sqrt(d.squaredNorm());
    }
    return true;
  }

  // Stride 7: every parameter's derivative in one pass.
  static ceres::CostFunction* Create(const ScanPairGeometry* geometry) {
    auto* cost =
        new ceres::DynamicAutoDiffCostFunction<ScanPairResidual, 7>(new ScanPairResidual(geometry));
    cost->AddParameterBlock(3);
    cost->AddParameterBlock(3);
    cost->AddParameterBlock(1);
    cost->SetNumResiduals(static_cast<int>(geometry->lines.size()));
    return cost;
  }

 private:
  const ScanPairGeometry* geometry_;
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_SCAN_SCAN_PAIR_RESIDUAL_H_
