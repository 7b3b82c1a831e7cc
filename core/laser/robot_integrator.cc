#include <calib/core/laser/robot_integrator.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

// The wheel angles are closed form (wheel_profile.h), and so is the robot's heading, θ(t) = θ_a +
// (r_r·ΔΦ_r − r_l·ΔΦ_l)/b (the slip effects do not turn the robot), so the position is a plain
// quadrature of R(θ(t))·(u, w) with u = v − γ_long·dv/dt and w = γ_lat·v·ω. Where the speeds are
// constant the body twist is constant and the motion is the exact SE(2) exponential. Where they
// vary, 4-point Gauss–Legendre panels are used; every discontinuity (new target, radius change,
// scan time) is a panel end, so the integrand is analytic on each panel. Its derivatives scale like
// 1/τ^k and ω^k, hence panels of half the shortest of τ and 1/ω have errors near 1e-14 m (the step
// model's error falls as (T/steps)² down to 5e-12 m at 3200 steps). integration_step_s is only a
// lower bound on the panel length: the default 0.002 s never binds, a larger value coarsens the
// sum. Work per interval is thus a few panels, whatever the step, and no path is stored.
//
// With constant speeds, a speed change at a boundary is a jump of v, and the longitudinal slip
// u = v − γ·dv/dt integrates to an impulse: a forward displacement of −γ·Δv at that instant. A
// scan taken exactly at the boundary (time_offset_s = 0) sees half of it, as if the speed changed
// along a short ramp centred on the boundary; so interval k moves by −γ·(v_{k+1} − v_{k−1})/2.
// A radius change is a change of the wheels, not an acceleration: it causes no impulse.
namespace calib {
namespace laser_sim_internal {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct Radii {
  double left = 0.0;
  double right = 0.0;
  double base = 0.0;
  // (v, ω) from wheel speeds (or their derivatives, for dv/dt).
  double Forward(const Eigen::Array2d& phi) const { return 0.5 * (left * phi(0) + right * phi(1)); }
  double Angular(const Eigen::Array2d& phi) const {
    return (right * phi(1) - left * phi(0)) / base;
  }
};

// exp of the constant body twist (u, w, ω) held for dt.
Pose2d TwistExp(double u, double w, double omega, double dt) {
  return Exp(Twist2d(u * dt, w * dt, omega * dt));
}

// The robot's motion over each scan window [t_k + δ, t_{k+1} + δ], never storing the path.
class RobotIntegrator {
 public:
  RobotIntegrator(const LaserSimOptions& options, const WheelProfile& profile)
      : profile_(profile),
        effects_(options.effects),
        before_{options.odometry.left_radius_m, options.odometry.right_radius_m,
                options.odometry.wheelbase_m},
        after_{options.effects.left_radius_after_m, options.effects.right_radius_after_m,
               options.odometry.wheelbase_m},
        change_s_(options.effects.radius_change_time_s >= 0.0 ? options.effects.radius_change_time_s
                                                              : kInfinity) {
    if (profile_.smooth()) {
      // The fastest turning rate sets the heading's time scale (see the top of the file).
      double omega_max = 0.0;
      for (const Radii& radii : {before_, after_}) {
        if (radii.base != 0.0) {
          omega_max =
              std::max(omega_max, (std::abs(radii.left) + std::abs(radii.right)) *
                                      std::abs(options.max_wheel_speed) / std::abs(radii.base));
        }
      }
      const double scale =
          omega_max > 0.0 ? std::min(profile_.tau(), 1.0 / omega_max) : profile_.tau();
      panel_s_ = std::max(options.integration_step_s, 0.5 * scale);
    }
  }

  std::vector<Pose2d> Integrate(const std::vector<double>& boundaries) const {
    const std::vector<SpeedSegment>& segments = profile_.segments();
    const double offset = effects_.time_offset_s;
    const size_t num_intervals = boundaries.size() - 1;
    std::vector<Pose2d> motions;
    motions.reserve(num_intervals);
    double t = boundaries[0] + offset;
    size_t cursor = 0;
    size_t segment = profile_.Find(t, &cursor);
    Pose2d motion = Pose2d::Zero();  // Since the last scan, in the robot frame at that scan.
    while (motions.size() < num_intervals) {
      const double next_scan = boundaries[motions.size() + 1] + offset;
      const double next_segment =
          segment + 1 < segments.size() ? segments[segment + 1].start_s : kInfinity;
      const double next_change = change_s_ > t ? change_s_ : kInfinity;
      const double next = std::min({next_scan, next_segment, next_change});
      if (next > t) {
        const Radii& radii = 0.5 * (t + next) < change_s_ ? before_ : after_;
        motion = profile_.smooth()
                     ? Compose(motion, SmoothPiece(segments[segment], radii, t, next))
                     : Compose(motion, ConstantPiece(segments[segment], radii, next - t));
      }
      t = next;
      Pose2d impulse = Pose2d::Zero();
      if (t == next_segment) {
        ++segment;
        if (!profile_.smooth() && effects_.longitudinal_slip_s != 0.0) {
          const Radii& radii = t < change_s_ ? before_ : after_;
          const double jump =
              radii.Forward(segments[segment].target) - radii.Forward(segments[segment - 1].target);
          impulse(0) = -effects_.longitudinal_slip_s * jump;
        }
      }
      if (t == next_scan) {
        // A scan at the instant of an impulse sees half of it (the centred-ramp convention).
        motions.push_back(Compose(motion, Pose2d(0.5 * impulse)));
        motion = 0.5 * impulse;
      } else {
        motion = Compose(motion, impulse);
      }
    }
    return motions;
  }

 private:
  Pose2d ConstantPiece(const SpeedSegment& segment, const Radii& radii, double dt) const {
    const double v = radii.Forward(segment.target);
    const double omega = radii.Angular(segment.target);
    return TwistExp(v, effects_.lateral_slip_s * v * omega, omega, dt);
  }

  // The motion over [a, b] inside one segment, in the robot frame at a: the heading is closed
  // form and the position ∫ R(θ)·(u, w) dt a 4-point Gauss–Legendre sum per panel.
  Pose2d SmoothPiece(const SpeedSegment& segment, const Radii& radii, double a, double b) const {
    static constexpr double kNodes[4] = {-0.8611363115940526, -0.3399810435848563,
                                         0.3399810435848563, 0.8611363115940526};
    static constexpr double kWeights[4] = {0.3478548451374538, 0.6521451548625461,
                                           0.6521451548625461, 0.3478548451374538};
    const double tau = profile_.tau();
    const Eigen::Array2d lag = segment.speed - segment.target;
    const Eigen::Array2d rotation_a = profile_.Rotation(segment, a - segment.start_s);
    const auto relative_heading = [&](double dt) {
      return radii.Angular(profile_.Rotation(segment, dt) - rotation_a);
    };
    const int panels = std::max(1, static_cast<int>(std::ceil((b - a) / panel_s_)));
    const double h = (b - a) / panels;
    double x = 0.0;
    double y = 0.0;
    for (int p = 0; p < panels; ++p) {
      double px = 0.0;
      double py = 0.0;
      for (int i = 0; i < 4; ++i) {
        const double dt = a + h * (p + 0.5 * (1.0 + kNodes[i])) - segment.start_s;
        const double decay = std::exp(-std::max(dt, 0.0) / tau);
        // Φ − Φ(a) = g·dt + (φ_a − g)·τ·(1 − e), φ = g + (φ_a − g)·e, dφ/dt = −(φ_a − g)·e/τ.
        const Eigen::Array2d rotation =
            segment.target * dt + lag * (tau * (1.0 - decay)) - rotation_a;
        const Eigen::Array2d speed = segment.target + lag * decay;
        const Eigen::Array2d accel = lag * (-decay / tau);
        const double v = radii.Forward(speed);
        const double omega = radii.Angular(speed);
        const double u = v - effects_.longitudinal_slip_s * radii.Forward(accel);
        const double w = effects_.lateral_slip_s * v * omega;
        const double theta = radii.Angular(rotation);
        const double c = std::cos(theta);
        const double s = std::sin(theta);
        px += kWeights[i] * (c * u - s * w);
        py += kWeights[i] * (s * u + c * w);
      }
      x += 0.5 * h * px;
      y += 0.5 * h * py;
    }
    return Pose2d(x, y, relative_heading(b - segment.start_s));
  }

  const WheelProfile& profile_;
  LaserEffects effects_;
  Radii before_;
  Radii after_;
  double change_s_;
  double panel_s_ = kInfinity;
};

}  // namespace

std::vector<Pose2d> IntegrateRobotMotions(const LaserSimOptions& options,
                                          const WheelProfile& profile,
                                          const std::vector<double>& boundaries) {
  return RobotIntegrator(options, profile).Integrate(boundaries);
}

}  // namespace laser_sim_internal
}  // namespace calib
