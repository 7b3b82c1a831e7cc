#ifndef CALIB_CORE_BEARING_BEARING_PARAMS_H_
#define CALIB_CORE_BEARING_BEARING_PARAMS_H_

#include <calib/core/param_info.h>

#include <Eigen/Core>
#include <array>
#include <cmath>

// The parameters of the bearing-only problem (Martinelli 2009): the metric set of Table 2, the
// observable set of eq. 5 that a bearing-only log determines, their vector layouts, contract
// names, units and readings.
namespace calib {

// The original parameters (Table 2 of the paper).
struct BearingMetricParams {
  double phi_rad = 0.0;
  double rho_m = 0.0;
  double psi_rad = 0.0;
  double delta_r = 1.0;
  double delta_l = 1.0;
  double delta_b = 1.0;
};

// The parameters a bearing-only log determines (eq. 5).
struct BearingParams {
  double phi_rad = 0.0;
  double psi_rad = 0.0;
  double eta_per_m = 0.0;  // η = δR/(2ρ).
  double delta = 1.0;      // δ = δL/δR.
  double xi_per_m = 0.0;   // ξ = δR/(B·δB).
};

inline BearingParams ObservableParams(const BearingMetricParams& m, double wheelbase_m) {
  BearingParams p;
  p.phi_rad = m.phi_rad;
  p.psi_rad = m.psi_rad;
  p.eta_per_m = m.delta_r / (2.0 * m.rho_m);
  p.delta = m.delta_l / m.delta_r;
  p.xi_per_m = m.delta_r / (wheelbase_m * m.delta_b);
  return p;
}

// The metric parameters once ρ is known (end of §7): δR = 2ρη, δL = δ·δR, δB = δR/(B·ξ).
inline BearingMetricParams MetricParams(const BearingParams& p, double rho_m, double wheelbase_m) {
  BearingMetricParams m;
  m.phi_rad = p.phi_rad;
  m.psi_rad = p.psi_rad;
  m.rho_m = rho_m;
  m.delta_r = 2.0 * rho_m * p.eta_per_m;
  m.delta_l = p.delta * m.delta_r;
  m.delta_b = m.delta_r / (wheelbase_m * p.xi_per_m);
  return m;
}

// Layout of the observable set as a vector (and of the calibration block of the bearing bundle
// adjustment, estimated in the scale gauge δR ≡ 1; see
// solvers/bearing/bearing_bundle_adjustment.h).
enum BearingParamIndex { kBearingPhi = 0, kBearingPsi, kBearingEta, kBearingDelta, kBearingXi };
inline constexpr int kNumBearingParams = 5;
using BearingParamVector = Eigen::Matrix<double, kNumBearingParams, 1>;
using BearingParamMatrix = Eigen::Matrix<double, kNumBearingParams, kNumBearingParams>;

// The metric set (φ, ψ, ρ, δR, δL, δB).
enum BearingMetricIndex {
  kBearingMetricPhi = 0,
  kBearingMetricPsi,
  kBearingMetricRho,
  kBearingMetricDeltaR,
  kBearingMetricDeltaL,
  kBearingMetricDeltaB
};
inline constexpr int kNumBearingMetricParams = 6;
using BearingMetricVector = Eigen::Matrix<double, kNumBearingMetricParams, 1>;
using BearingMetricMatrix = Eigen::Matrix<double, kNumBearingMetricParams, kNumBearingMetricParams>;

// The contract's names (CONTRACT.md), in the order of the vectors above.
inline constexpr std::array<const char*, kNumBearingParams> kBearingParamNames = {
    "phi", "psi", "eta", "delta", "xi"};
inline constexpr std::array<const char*, kNumBearingMetricParams> kBearingMetricNames = {
    "phi", "psi", "rho", "delta_r", "delta_l", "delta_b"};

// Name, unit and reading of each parameter, in the same orders.
inline constexpr ParamInfo kBearingParams[kNumBearingParams] = {
    {"phi", "rad", true, 180.0 / M_PI, "deg"},
    {"psi", "rad", true, 180.0 / M_PI, "deg"},
    {"eta", "1/m", false, 1.0, "1/m"},
    {"delta", "", false, 1.0, ""},
    {"xi", "1/m", false, 1.0, "1/m"}};
inline constexpr ParamInfo kBearingMetricParams[kNumBearingMetricParams] = {
    {"phi", "rad", true, 180.0 / M_PI, "deg"},
    {"psi", "rad", true, 180.0 / M_PI, "deg"},
    {"rho", "m", false, 1.0, "m"},
    {"delta_r", "", false, 1.0, ""},
    {"delta_l", "", false, 1.0, ""},
    {"delta_b", "", false, 1.0, ""}};

inline BearingParamVector ToVector(const BearingParams& p) {
  BearingParamVector v;
  v << p.phi_rad, p.psi_rad, p.eta_per_m, p.delta, p.xi_per_m;
  return v;
}

inline BearingParams BearingParamsFromVector(const BearingParamVector& v) {
  BearingParams p;
  p.phi_rad = v(kBearingPhi);
  p.psi_rad = v(kBearingPsi);
  p.eta_per_m = v(kBearingEta);
  p.delta = v(kBearingDelta);
  p.xi_per_m = v(kBearingXi);
  return p;
}

inline BearingMetricVector ToVector(const BearingMetricParams& m) {
  BearingMetricVector v;
  v << m.phi_rad, m.psi_rad, m.rho_m, m.delta_r, m.delta_l, m.delta_b;
  return v;
}

}  // namespace calib

#endif  // CALIB_CORE_BEARING_BEARING_PARAMS_H_
