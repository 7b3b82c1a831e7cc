#ifndef CALIB_CORE_BEARING_BEARING_MODEL_H_
#define CALIB_CORE_BEARING_BEARING_MODEL_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_params.h>
#include <calib/core/diff_drive.h>
#include <calib/core/se2.h>
#include <calib/core/timing/encoder_integration.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <complex>
#include <utility>
#include <vector>

// The bearing-only model of Martinelli, "Using the Distribution Theory to Simultaneously
// Calibrate the Sensors of a Mobile Robot", INRIA RR-6796, 2009 (seed 001). Equation numbers
// refer to that report. Scalar-generic where a solver may need derivatives (ceres::Jet).
//
// Conventions (CONTRACT.md): the landmark is the world origin; the sensor sits at
// (ρ cos φ, ρ sin φ) in the robot frame with heading φ + ψ; wheel travel = r × wheel rotation;
// v = (δR·vR + δL·vL)/2, ω = (δR·vR − δL·vL)/(δB·B) with vR, vL the nominal wheel speeds.
namespace calib {

// ---------------------------------------------------------------------------------------------
// Observation model.

// robot_T_sensor: position (ρ cos φ, ρ sin φ), heading φ + ψ.
template <typename T>
Pose2<T> RobotTSensor(const T& phi, const T& rho, const T& psi) {
  using std::cos;
  using std::sin;
  return Pose2<T>(rho * cos(phi), rho * sin(phi), phi + psi);
}

// The geometric definition: the landmark's (world origin) direction in the sensor frame,
// wrapped to (−π, π].
template <typename T>
T BearingFromPose(const Pose2<T>& world_T_robot, const T& phi, const T& rho, const T& psi) {
  using std::atan2;
  const Pose2<T> world_T_sensor = Compose(world_T_robot, RobotTSensor(phi, rho, psi));
  return WrapAngle(atan2(-world_T_sensor(1), -world_T_sensor(0)) - world_T_sensor(2));
}

// γ = θR − atan2(yR, xR) + φ and μ = ρ/D with D = ‖(xR, yR)‖ (eq. 3).
template <typename T>
void GammaMuFromPose(const Pose2<T>& world_T_robot, const T& phi, const T& rho, T* gamma, T* mu) {
  using std::atan2;
  using std::sqrt;
  const T x = world_T_robot(0);
  const T y = world_T_robot(1);
  *gamma = world_T_robot(2) - atan2(y, x) + phi;
  *mu = rho / sqrt(x * x + y * y);
}

// Eq. 3 (and the output of eq. 6): β = −atan(sin γ/(μ + cos γ)) − ψ, plus π when
// μ + cos γ > 0 (γ− ≤ γ ≤ γ+). With atan2 the two branches are one expression:
// β = π − atan2(sin γ, μ + cos γ) − ψ (mod 2π); unlike the paper's branches it needs no μ < 1.
template <typename T>
T BearingFromGammaMu(const T& gamma, const T& mu, const T& psi) {
  using std::atan2;
  using std::cos;
  using std::sin;
  return WrapAngle(T(M_PI) - atan2(sin(gamma), mu + cos(gamma)) - psi);
}

// Eq. 6: d(μ, γ)/dt for nominal wheel speeds vR, vL (m/s).
template <typename T>
void GammaMuRates(const T& mu, const T& gamma, const T& right_mps, const T& left_mps, const T& phi,
                  const T& eta, const T& delta, const T& xi, T* mu_dot, T* gamma_dot) {
  using std::cos;
  using std::sin;
  const T forward = eta * (right_mps + delta * left_mps);  // v/ρ.
  *mu_dot = -mu * mu * forward * cos(gamma - phi);
  *gamma_dot = xi * (right_mps - delta * left_mps) - mu * forward * sin(gamma - phi);
}

// ---------------------------------------------------------------------------------------------
// Circular runs: vR = ν, vL = q·ν, and s = ∫ν dt is the nominal travel of the right wheel (the
// paper calls it the curve length; it is the right wheel's, not the robot centre's).

// Eq. 11.
template <typename T>
T EtaQ(const T& eta, const T& delta, const T& q) {
  return eta * (T(1) + q * delta);
}
template <typename T>
T XiQ(const T& xi, const T& delta, const T& q) {
  return xi * (T(1) - q * delta);
}

// Eq. 13.
template <typename T>
T Psi1(const T& phi, const T& eta_q, const T& xi_q) {
  using std::cos;
  using std::sin;
  return (xi_q - eta_q * sin(phi)) / (eta_q * cos(phi));
}
template <typename T>
T Psi2(const T& mu, const T& gamma, const T& phi, const T& eta_q) {
  using std::cos;
  using std::sin;
  return mu * eta_q * cos(phi) / sin(gamma);
}
template <typename T>
T Psi3(const T& mu, const T& gamma) {
  using std::cos;
  using std::sin;
  return (mu + cos(gamma)) / sin(gamma);
}

// The observable state of a circular run (eq. 15).
template <typename T>
struct CircularState {
  T A;
  T V;
  T L;
};

template <typename T>
CircularState<T> CircularStateFromGammaMu(const T& mu, const T& gamma, const T& phi, const T& psi,
                                          const T& eta_q, const T& xi_q) {
  using std::atan;
  const T p1 = Psi1(phi, eta_q, xi_q);
  const T p2 = Psi2(mu, gamma, phi, eta_q);
  const T p3 = Psi3(mu, gamma);
  return CircularState<T>{(p1 - p3) / (T(1) + p1 * p3), p2 * (T(1) + p1 * p3) / (T(1) + p3 * p3),
                          psi - atan(p1)};
}

// Eq. 14: dA/ds and dV/ds.
template <typename T>
void CircularStateRates(const T& a, const T& v, const T& xi_q, T* a_rate, T* v_rate) {
  *a_rate = (T(1) + a * a) * (xi_q - v);
  *v_rate = a * v * (T(2) * v - xi_q);
}

// Eq. 14, output: β = −atan A − L + S_p·π/2, wrapped.
template <typename T>
T BearingFromA(const T& a, const T& l, int s_p) {
  using std::atan;
  return WrapAngle(-atan(a) - l + T(s_p * M_PI / 2.0));
}

// Inverts eqs. 13 and 15 for the state (end of §7): Ψ3 from A and Ψ1, Ψ2 from V, then
// μ/sin γ = Ψ2/(ηq cos φ) and cot γ = Ψ3 − μ/sin γ, with μ > 0 fixing γ's half-plane.
template <typename T>
void GammaMuFromState(const T& a, const T& v, const T& phi, const T& eta_q, const T& xi_q, T* gamma,
                      T* mu) {
  using std::atan2;
  using std::cos;
  using std::sqrt;
  const T p1 = Psi1(phi, eta_q, xi_q);
  const T p3 = (p1 - a) / (T(1) + a * p1);
  const T p2 = v * (T(1) + p3 * p3) / (T(1) + p1 * p3);
  const T mu_over_sin = p2 / (eta_q * cos(phi));
  const T cot_gamma = p3 - mu_over_sin;
  const T sign = mu_over_sin < T(0) ? T(-1) : T(1);
  const T sin_gamma = sign / sqrt(T(1) + cot_gamma * cot_gamma);
  *gamma = atan2(sin_gamma, cot_gamma * sin_gamma);
  *mu = mu_over_sin * sin_gamma;
}

// Eq. 17 (the first integral of eq. 14, eq. 16).
template <typename T>
T KFromState(const T& a, const T& v, const T& xi_q) {
  return (T(1) + a * a) * v * v / (T(2) * v - xi_q);
}

// Eq. 21. atan2 with a non-negative second argument is the paper's atan, also where A0·V0 = 0.
template <typename T>
T CFromKV(const T& k, const T& v0, const T& xi_q) {
  using std::atan2;
  using std::sqrt;
  T radicand = -v0 * v0 + T(2) * k * v0 - xi_q * k;  // = (A0·V0)² by eq. 16.
  if (radicand < T(0)) radicand = T(0);
  const T numerator = xi_q * k + (xi_q - T(2) * k) * v0;
  const T sign = xi_q < T(0) ? T(-1) : T(1);
  return atan2(sign * numerator, sign * xi_q * sqrt(radicand));
}

// Eq. 23.
template <typename T>
T WFromS(const T& c, const T& xi_q, const T& s, int s_w) {
  using std::tan;
  return xi_q * tan(c + T(s_w) * xi_q * s);
}

// Eq. 24.
template <typename T>
T VFromW(const T& w, const T& k, const T& xi_q, int s_v) {
  using std::sqrt;
  T radicand = k * (k - xi_q) * (w * w + xi_q * xi_q);
  if (radicand < T(0)) radicand = T(0);
  const T d = T(2) * k - xi_q;
  return (xi_q * k * d + k * w * w + T(s_v) * w * sqrt(radicand)) / (d * d + w * w);
}

// Eq. 25: β = S_y·atan(√((k(2V − ξq) − V²)/V²)) − L + S_p·π/2, wrapped.
template <typename T>
T BearingFromV(const T& v, const T& k, const T& xi_q, const T& l, int s_y, int s_p) {
  using std::atan;
  using std::sqrt;
  T radicand = (k * (T(2) * v - xi_q) - v * v) / (v * v);
  if (radicand < T(0)) radicand = T(0);
  return WrapAngle(T(s_y) * atan(sqrt(radicand)) - l + T(s_p * M_PI / 2.0));
}

// Eq. 26: the j-th node; eq. 28: the j-th mirror point.
inline double NodeFromC(double c, double xi_q, int s_w, int j) {
  return -s_w * c / xi_q + j * M_PI / xi_q + s_w * M_PI / (2.0 * xi_q);
}
inline double MirrorPointFromC(double c, double xi_q, int s_w, int j) {
  return -s_w * c / xi_q + j * M_PI / xi_q;
}

// Eq. 36: k from the bearings at two consecutive mirror points.
inline double KFromMirrorBearings(double bearing_m1, double bearing_m2, double xi_q) {
  const double t = std::tan(0.5 * (bearing_m1 - bearing_m2));
  return xi_q / (1.0 - t * t);
}

// ---------------------------------------------------------------------------------------------
// The observation function of a circular run in closed form. On a circle the sensor frame turns
// at the constant rate ξq about the robot's centre of rotation, so in the sensor frame the
// landmark runs on a circle about that centre, C, at rate −ξq. As complex numbers,
//   p(s) = C·(1 + r·e^{−iξq(s − s_n)}),   β(s) = θC + arg(1 + r·e^{iχ}),   χ = −ξq(s − s_n),
// with θC = arg C and r real: ±(landmark–centre distance)/(sensor–centre distance). The nodes
// s_n + jπ/ξq (eq. 26) are where the landmark crosses the line through the sensor and C; β is
// symmetric about them, so β(s) + β(2s_n − s) = 2θC (mod 2π), which is eq. 35 with
// θC ≡ π/2 − L (mod π). In the paper's quantities: k = ξq/(1 − r²) (eq. 17),
// V = ξq + dβ/ds = ξq(1 + r cos χ)/(1 + 2r cos χ + r²) and A = −r sin χ/(1 + r cos χ) (eq. 14).
struct BearingCircle {
  double xi_q_per_m = 0.0;          // ξq: the sensor frame turns by ξq per metre of s.
  double node_m = 0.0;              // s_n, a node.
  double center_bearing_rad = 0.0;  // θC.
  double ratio = 0.0;               // r.
};

template <typename T>
T CircleBearing(const T& s, const T& xi_q, const T& node, const T& center_bearing, const T& ratio) {
  using std::atan2;
  using std::cos;
  using std::sin;
  const T chi = -xi_q * (s - node);
  return WrapAngle(center_bearing + atan2(ratio * sin(chi), T(1) + ratio * cos(chi)));
}

inline double CircleBearing(const BearingCircle& c, double s) {
  return CircleBearing(s, c.xi_q_per_m, c.node_m, c.center_bearing_rad, c.ratio);
}

// dβ/ds.
inline double CircleBearingSlope(const BearingCircle& c, double s) {
  const double chi = -c.xi_q_per_m * (s - c.node_m);
  const double r = c.ratio;
  return -c.xi_q_per_m * (r * r + r * std::cos(chi)) / (1.0 + 2.0 * r * std::cos(chi) + r * r);
}

// Eq. 17 in terms of r.
inline double CircleK(const BearingCircle& c) { return c.xi_q_per_m / (1.0 - c.ratio * c.ratio); }

// L modulo π (in [0, π)): θC ≡ π/2 − L.
inline double CircleLModPi(const BearingCircle& c) {
  double l = std::fmod(M_PI / 2.0 - c.center_bearing_rad, M_PI);
  if (l < 0.0) l += M_PI;
  return l;
}

// A(s) and V(s) of eq. 15 on the circle.
inline void CircleState(const BearingCircle& c, double s, double* a, double* v) {
  const double chi = -c.xi_q_per_m * (s - c.node_m);
  const double r = c.ratio;
  *a = -r * std::sin(chi) / (1.0 + r * std::cos(chi));
  *v = c.xi_q_per_m * (1.0 + r * std::cos(chi)) / (1.0 + 2.0 * r * std::cos(chi) + r * r);
}

// The same circle with its node moved to [s_origin, s_origin + π/|ξq|): each half-period shift
// flips the sign of r.
inline BearingCircle NormalizeCircle(BearingCircle c, double s_origin) {
  const double half = M_PI / std::abs(c.xi_q_per_m);
  const double shifts = std::floor((c.node_m - s_origin) / half);
  c.node_m -= shifts * half;
  if (std::fmod(std::abs(shifts), 2.0) == 1.0) c.ratio = -c.ratio;
  if (c.node_m >= s_origin + half) c.node_m -= half, c.ratio = -c.ratio;  // Rounding.
  if (c.node_m < s_origin) c.node_m += half, c.ratio = -c.ratio;
  return c;
}

// The circle of a run at fixed q from its start pose (s = 0 at world_T_robot_start).
// Requires ξq ≠ 0 and a sensor away from the centre of rotation.
inline BearingCircle CircleFromStart(const BearingMetricParams& m, double wheelbase_m, double q,
                                     const Pose2d& world_T_robot_start) {
  const BearingParams p = ObservableParams(m, wheelbase_m);
  const double xi_q = XiQ(p.xi_per_m, p.delta, q);
  const double radius = m.rho_m * EtaQ(p.eta_per_m, p.delta, q) / xi_q;  // v/ω.
  const Pose2d world_T_center = Compose(world_T_robot_start, Pose2d(0.0, radius, 0.0));
  const Pose2d world_T_sensor =
      Compose(world_T_robot_start, RobotTSensor(m.phi_rad, m.rho_m, m.psi_rad));
  const Pose2d sensor_T_world = Inverse(world_T_sensor);
  const Pose2d center = Compose(sensor_T_world, Pose2d(world_T_center(0), world_T_center(1), 0));
  const Pose2d landmark = Compose(sensor_T_world, Pose2d(Pose2d::Zero()));
  // r·e^{iξq·s_n} = (p(0) − C)/C.
  const std::complex<double> cc(center(0), center(1));
  const std::complex<double> rel = (std::complex<double>(landmark(0), landmark(1)) - cc) / cc;
  BearingCircle c;
  c.xi_q_per_m = xi_q;
  c.center_bearing_rad = std::arg(cc);
  c.ratio = std::abs(rel);
  c.node_m = std::arg(rel) / xi_q;
  return NormalizeCircle(c, 0.0);
}

}  // namespace calib

#endif  // CALIB_CORE_BEARING_BEARING_MODEL_H_
