#include <calib/core/bearing/bearing_model.h>
#include <calib/core/bearing/bearing_simulator.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

namespace calib {
namespace {

constexpr double kB = 0.5;  // Nominal wheelbase of §8.1.

BearingMetricParams Table2() { return BearingMetricParams{0.0, 0.3, M_PI / 2, 0.99, 1.006, 0.97}; }

BearingMetricParams RandomParams(std::mt19937* rng) {
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), factor(0.9, 1.1), rho(0.1, 0.5);
  return BearingMetricParams{angle(*rng),  rho(*rng),    angle(*rng),
                             factor(*rng), factor(*rng), factor(*rng)};
}

// The robot after travel s of the right wheel on the circle of ratio q (v = ρηq·ν, ω = ξq·ν).
Pose2d PoseOnCircle(const BearingMetricParams& m, double q, const Pose2d& start, double s) {
  const BearingParams p = ObservableParams(m, kB);
  return Compose(start, ArcDisplacement(m.rho_m * EtaQ(p.eta_per_m, p.delta, q) * s,
                                        XiQ(p.xi_per_m, p.delta, q) * s));
}

double Bearing(const BearingMetricParams& m, const Pose2d& pose) {
  return BearingFromPose(pose, m.phi_rad, m.rho_m, m.psi_rad);
}

CircularState<double> StateAt(const BearingMetricParams& m, double q, const Pose2d& pose) {
  const BearingParams p = ObservableParams(m, kB);
  double gamma = 0.0, mu = 0.0;
  GammaMuFromPose(pose, m.phi_rad, m.rho_m, &gamma, &mu);
  return CircularStateFromGammaMu(mu, gamma, m.phi_rad, m.psi_rad, EtaQ(p.eta_per_m, p.delta, q),
                                  XiQ(p.xi_per_m, p.delta, q));
}

void ExpectAngleNear(double a, double b, double tol) { EXPECT_NEAR(WrapAngle(a - b), 0.0, tol); }

// ---------------------------------------------------------------------------------------------
// Observation model (eqs. 1–6).

TEST(BearingModelTest, Table2GivesTable3Parameters) {
  const BearingParams p = ObservableParams(Table2(), kB);
  EXPECT_NEAR(p.eta_per_m, 1.65, 1e-12);
  EXPECT_NEAR(p.delta, 1.01616, 1e-5);
  EXPECT_NEAR(p.xi_per_m, 2.0412, 1e-4);
  const BearingMetricParams back = MetricParams(p, 0.3, kB);
  EXPECT_NEAR(back.delta_r, 0.99, 1e-12);
  EXPECT_NEAR(back.delta_l, 1.006, 1e-12);
  EXPECT_NEAR(back.delta_b, 0.97, 1e-12);
}

TEST(BearingModelTest, GammaMuFormEqualsGeometricDefinition) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> xy(-3.0, 3.0), angle(-M_PI, M_PI);
  for (int i = 0; i < 2000; ++i) {
    const BearingMetricParams m = RandomParams(&rng);
    const Pose2d pose(xy(rng), xy(rng), angle(rng));
    double gamma = 0.0, mu = 0.0;
    GammaMuFromPose(pose, m.phi_rad, m.rho_m, &gamma, &mu);
    const double geometric = Bearing(m, pose);
    EXPECT_GT(geometric, -M_PI);
    EXPECT_LE(geometric, M_PI);
    ExpectAngleNear(BearingFromGammaMu(gamma, mu, m.psi_rad), geometric, 1e-12);
    // The paper's two branches of eq. 3 (γ± solve cos γ = −μ), defined for μ < 1.
    if (mu < 1.0) {
      const double g = WrapAngle(gamma);
      const double g_plus = std::acos(-mu);
      const double base = -std::atan(std::sin(g) / (mu + std::cos(g))) - m.psi_rad;
      const double paper = (-g_plus <= g && g <= g_plus) ? base + M_PI : base;
      ExpectAngleNear(paper, geometric, 1e-9);
    }
  }
}

TEST(BearingModelTest, GammaMuRatesMatchTheKinematics) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> xy(-3.0, 3.0), angle(-M_PI, M_PI), speed(-0.2, 0.2);
  for (int i = 0; i < 200; ++i) {
    const BearingMetricParams m = RandomParams(&rng);
    const BearingParams p = ObservableParams(m, kB);
    const Pose2d pose(xy(rng), xy(rng), angle(rng));
    const double right = speed(rng), left = speed(rng);
    // Eqs. 1–2: the true pose derivative.
    const double v = 0.5 * (m.delta_r * right + m.delta_l * left);
    const double w = (m.delta_r * right - m.delta_l * left) / (m.delta_b * kB);
    const Pose2d rate(v * std::cos(pose(2)), v * std::sin(pose(2)), w);
    const double h = 1e-6;
    double g1, mu1, g0, mu0, g, mu;
    GammaMuFromPose(Pose2d(pose + h * rate), m.phi_rad, m.rho_m, &g1, &mu1);
    GammaMuFromPose(Pose2d(pose - h * rate), m.phi_rad, m.rho_m, &g0, &mu0);
    GammaMuFromPose(pose, m.phi_rad, m.rho_m, &g, &mu);
    double mu_dot = 0.0, gamma_dot = 0.0;
    GammaMuRates(mu, g, right, left, m.phi_rad, p.eta_per_m, p.delta, p.xi_per_m, &mu_dot,
                 &gamma_dot);
    EXPECT_NEAR(mu_dot, (mu1 - mu0) / (2 * h), 1e-6 * (1 + std::abs(mu_dot)));
    EXPECT_NEAR(gamma_dot, WrapAngle(g1 - g0) / (2 * h), 1e-6 * (1 + std::abs(gamma_dot)));
  }
}

// ---------------------------------------------------------------------------------------------
// Circular runs (eqs. 11–36).

struct CircleCase {
  BearingMetricParams m;
  double q;
  Pose2d start;
};

std::vector<CircleCase> CircleCases() {
  std::vector<CircleCase> cases;
  for (double q : {0.9, 0.0, -1.0}) {
    cases.push_back({Table2(), q, Pose2d(0.0, -1.0, 0.0)});
    cases.push_back({Table2(), q, Pose2d(2.0, 1.0, 2.0)});
  }
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-2.0, 2.0), angle(-M_PI, M_PI), q(-1.5, 2.5);
  for (int i = 0; i < 20; ++i) {
    CircleCase c{RandomParams(&rng), q(rng), Pose2d(xy(rng), xy(rng), angle(rng))};
    c.m.phi_rad = std::clamp(c.m.phi_rad, -1.4, 1.4);  // Eq. 13 needs cos φ ≠ 0.
    cases.push_back(c);
  }
  return cases;
}

TEST(BearingModelTest, CircularStateFollowsEq14AndKeepsKAndL) {
  for (const CircleCase& c : CircleCases()) {
    const BearingParams p = ObservableParams(c.m, kB);
    const double xi_q = XiQ(p.xi_per_m, p.delta, c.q);
    const double period = 2 * M_PI / std::abs(xi_q);
    const CircularState<double> s0 = StateAt(c.m, c.q, c.start);
    const double k0 = KFromState(s0.A, s0.V, xi_q);
    for (int i = 0; i < 40; ++i) {
      const double s = period * (i + 0.37) / 40;
      const CircularState<double> st = StateAt(c.m, c.q, PoseOnCircle(c.m, c.q, c.start, s));
      if (std::abs(st.A) > 50 || std::abs(st.V) > 50) continue;  // Near Ψ singularities.
      const double h = 1e-6 * period;
      const CircularState<double> up = StateAt(c.m, c.q, PoseOnCircle(c.m, c.q, c.start, s + h));
      const CircularState<double> dn = StateAt(c.m, c.q, PoseOnCircle(c.m, c.q, c.start, s - h));
      double a_rate = 0.0, v_rate = 0.0;
      CircularStateRates(st.A, st.V, xi_q, &a_rate, &v_rate);
      EXPECT_NEAR((up.A - dn.A) / (2 * h), a_rate, 1e-5 * (1 + std::abs(a_rate)));
      EXPECT_NEAR((up.V - dn.V) / (2 * h), v_rate, 1e-5 * (1 + std::abs(v_rate)));
      EXPECT_NEAR(KFromState(st.A, st.V, xi_q), k0, 1e-9 * (1 + std::abs(k0)));  // Eq. 16.
      EXPECT_NEAR(st.L, s0.L, 1e-12);
      // Eq. 14's output: β = −atan A − L + S_p·π/2 for S_p = +1 or −1.
      const double beta = Bearing(c.m, PoseOnCircle(c.m, c.q, c.start, s));
      const double e_plus = std::abs(WrapAngle(BearingFromA(st.A, st.L, 1) - beta));
      const double e_minus = std::abs(WrapAngle(BearingFromA(st.A, st.L, -1) - beta));
      EXPECT_LT(std::min(e_plus, e_minus), 1e-9);
    }
  }
}

TEST(BearingModelTest, ClosedFormCircleEqualsGeometryAndPaperQuantities) {
  for (const CircleCase& c : CircleCases()) {
    const BearingParams p = ObservableParams(c.m, kB);
    const double xi_q = XiQ(p.xi_per_m, p.delta, c.q);
    const BearingCircle circle = CircleFromStart(c.m, kB, c.q, c.start);
    EXPECT_EQ(circle.xi_q_per_m, xi_q);
    EXPECT_GE(circle.node_m, 0.0);
    EXPECT_LT(circle.node_m, M_PI / std::abs(xi_q));
    const CircularState<double> s0 = StateAt(c.m, c.q, c.start);
    // k (eq. 17) = ξq/(1 − r²); L ≡ π/2 − θC (mod π).
    EXPECT_NEAR(CircleK(circle), KFromState(s0.A, s0.V, xi_q),
                1e-9 * (1 + std::abs(CircleK(circle))));
    const double l_diff = std::fmod(CircleLModPi(circle) - s0.L, M_PI);
    EXPECT_NEAR(std::min(std::abs(l_diff), M_PI - std::abs(l_diff)), 0.0, 1e-10);
    const double period = 2 * M_PI / std::abs(xi_q);
    for (int i = 0; i < 50; ++i) {
      const double s = period * (i + 0.21) / 25;  // Two periods.
      const Pose2d pose = PoseOnCircle(c.m, c.q, c.start, s);
      ExpectAngleNear(CircleBearing(circle, s), Bearing(c.m, pose), 1e-10);
      const CircularState<double> st = StateAt(c.m, c.q, pose);
      double a = 0.0, v = 0.0;
      CircleState(circle, s, &a, &v);
      if (std::abs(st.A) < 1e3) {
        EXPECT_NEAR(a, st.A, 1e-8 * (1 + std::abs(a)));
      }
      if (std::abs(st.V) < 1e3) {
        EXPECT_NEAR(v, st.V, 1e-8 * (1 + std::abs(v)));
      }
      // V = ξq + dβ/ds (eq. 14).
      EXPECT_NEAR(v, xi_q + CircleBearingSlope(circle, s), 1e-9 * (1 + std::abs(v)));
    }
  }
}

TEST(BearingModelTest, ObservationIsPeriodicAndSymmetricAboutNodes) {
  // Eq. 31 and Theorem 1 (eq. 35) on the geometric bearings: with c from eq. 21 and the S_w
  // that fits, the nodes of eq. 26 are centres of symmetry: β(s) + β(2s_n − s) = π − 2L (mod 2π),
  // which implies the paper's −2L (mod π).
  for (const CircleCase& c : CircleCases()) {
    const BearingParams p = ObservableParams(c.m, kB);
    const double xi_q = XiQ(p.xi_per_m, p.delta, c.q);
    const double period = 2 * M_PI / std::abs(xi_q);
    const CircularState<double> s0 = StateAt(c.m, c.q, c.start);
    const double k = KFromState(s0.A, s0.V, xi_q);
    const double cc = CFromKV(k, s0.V, xi_q);
    const BearingCircle circle = CircleFromStart(c.m, kB, c.q, c.start);
    const auto beta = [&](double s) { return Bearing(c.m, PoseOnCircle(c.m, c.q, c.start, s)); };
    int s_w_found = 0;
    for (int s_w : {1, -1}) {
      const double node = NodeFromC(cc, xi_q, s_w, 3);
      double worst = 0.0;
      for (int i = 0; i < 20; ++i) {
        const double s = period * i / 20.0;
        worst =
            std::max(worst, std::abs(WrapAngle(beta(s) + beta(2 * node - s) - (M_PI - 2 * s0.L))));
      }
      if (worst < 1e-9) s_w_found = s_w;
    }
    ASSERT_NE(s_w_found, 0) << "no S_w makes eq. 26's nodes centres of symmetry";
    // The closed-form circle's node is one of them.
    const double node = NodeFromC(cc, xi_q, s_w_found, 0);
    const double offset = std::fmod(std::abs(node - circle.node_m), 0.5 * period);
    EXPECT_NEAR(std::min(offset, 0.5 * period - offset), 0.0, 1e-9 * period);
    for (int i = 0; i < 20; ++i) {
      const double s = period * (i + 0.5) / 20.0;
      ExpectAngleNear(beta(s + period), beta(s), 1e-9);
    }
    // w (eq. 23) has period π/|ξq| and changes sign under reflection about a mirror point
    // (Lemma 1).
    const double mirror = MirrorPointFromC(cc, xi_q, s_w_found, 1);
    for (double s : {0.1 * period, 0.33 * period}) {
      const double w = WFromS(cc, xi_q, s, s_w_found);
      EXPECT_NEAR(WFromS(cc, xi_q, s + 0.5 * period, s_w_found), w, 1e-7 * (1 + std::abs(w)));
      EXPECT_NEAR(WFromS(cc, xi_q, 2 * mirror - s, s_w_found), -w, 1e-7 * (1 + std::abs(w)));
    }
    // Eq. 36: k from the bearings at two consecutive mirror points.
    const double k36 =
        KFromMirrorBearings(beta(mirror), beta(mirror + M_PI / std::abs(xi_q)), xi_q);
    EXPECT_NEAR(k36, k, 1e-8 * (1 + std::abs(k)));
  }
}

TEST(BearingModelTest, Eqs23To25ReproduceTheObservation) {
  for (const CircleCase& c : CircleCases()) {
    const BearingParams p = ObservableParams(c.m, kB);
    const double xi_q = XiQ(p.xi_per_m, p.delta, c.q);
    const double period = 2 * M_PI / std::abs(xi_q);
    const CircularState<double> s0 = StateAt(c.m, c.q, c.start);
    const double k = KFromState(s0.A, s0.V, xi_q);
    const double cc = CFromKV(k, s0.V, xi_q);
    // S_w: w(0) from eq. 23 must give V0 through eq. 24 and dV/ds of eq. 14.
    int s_w = 0;
    for (int candidate : {1, -1}) {
      const double h = 1e-6 * period;
      for (int s_v : {1, -1}) {
        const double v0 = VFromW(WFromS(cc, xi_q, 0.0, candidate), k, xi_q, s_v);
        const double vh = VFromW(WFromS(cc, xi_q, h, candidate), k, xi_q, s_v);
        const double slope = s0.A * s0.V * (2 * s0.V - xi_q);
        if (std::abs(v0 - s0.V) < 1e-9 * (1 + std::abs(v0)) &&
            std::abs((vh - v0) / h - slope) < 1e-4 * (1 + std::abs(slope))) {
          s_w = candidate;
        }
      }
    }
    ASSERT_NE(s_w, 0);
    bool saw_k_node = false;
    for (int i = 0; i < 60; ++i) {
      const double s = period * (i + 0.3) / 60;
      const CircularState<double> st = StateAt(c.m, c.q, PoseOnCircle(c.m, c.q, c.start, s));
      const double w = WFromS(cc, xi_q, s, s_w);
      if (std::abs(w) > 1e6) continue;
      const double tol = 1e-7 * (1 + std::abs(st.V));
      const bool v_ok = std::abs(VFromW(w, k, xi_q, 1) - st.V) < tol ||
                        std::abs(VFromW(w, k, xi_q, -1) - st.V) < tol;
      EXPECT_TRUE(v_ok) << "eq. 24 misses V at s = " << s;
      const double beta = Bearing(c.m, PoseOnCircle(c.m, c.q, c.start, s));
      double best = 1e9;
      for (int s_y : {1, -1}) {
        for (int s_p : {1, -1}) {
          best = std::min(best,
                          std::abs(WrapAngle(BearingFromV(st.V, k, xi_q, st.L, s_y, s_p) - beta)));
        }
      }
      EXPECT_LT(best, 1e-7) << "eq. 25 misses β at s = " << s;
      saw_k_node |= st.V * xi_q < 0.0;
    }
    // k-nodes (V = 0) exist if and only if k·ξq < 0 (§6.2).
    if (k * xi_q > 0) {
      EXPECT_FALSE(saw_k_node);
    }
  }
}

TEST(BearingModelTest, StateInversionRecoversGammaAndMu) {
  for (const CircleCase& c : CircleCases()) {
    const BearingParams p = ObservableParams(c.m, kB);
    const double eta_q = EtaQ(p.eta_per_m, p.delta, c.q);
    const double xi_q = XiQ(p.xi_per_m, p.delta, c.q);
    for (double s : {0.0, 0.7, 1.9}) {
      const Pose2d pose = PoseOnCircle(c.m, c.q, c.start, s);
      double gamma = 0.0, mu = 0.0;
      GammaMuFromPose(pose, c.m.phi_rad, c.m.rho_m, &gamma, &mu);
      const CircularState<double> st = StateAt(c.m, c.q, pose);
      double gamma_back = 0.0, mu_back = 0.0;
      GammaMuFromState(st.A, st.V, c.m.phi_rad, eta_q, xi_q, &gamma_back, &mu_back);
      EXPECT_NEAR(mu_back, mu, 1e-8 * mu);
      ExpectAngleNear(gamma_back, gamma, 1e-8);
    }
  }
}

TEST(BearingModelTest, NormalizeCircleKeepsTheFunction) {
  const BearingCircle c{1.3, 7.9, 0.4, -1.7};
  const BearingCircle n = NormalizeCircle(c, -0.2);
  EXPECT_GE(n.node_m, -0.2);
  EXPECT_LT(n.node_m, -0.2 + M_PI / 1.3);
  for (double s : {-3.0, 0.0, 0.5, 4.0})
    ExpectAngleNear(CircleBearing(n, s), CircleBearing(c, s), 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Encoder integration and its covariance.

std::vector<EncoderSample> WigglyOdometry(int n, double dt, std::mt19937* rng) {
  std::uniform_real_distribution<double> step(0.0, 0.2);
  std::vector<EncoderSample> out{{0.0, 0.0, 0.0, 0}};
  for (int i = 1; i < n; ++i) {
    const EncoderSample& prev = out.back();
    const double t = i * dt;
    out.push_back({t, prev.left_rad + step(*rng) * (1.2 + std::sin(t)),
                   prev.right_rad + step(*rng) * (1.0 + std::cos(0.5 * t)), 0});
  }
  return out;
}

TEST(BearingModelTest, IntegrateEncodersMatchesTheSimulatedTruth) {
  BearingSimOptions o;
  o.encoder_noise_k = 0.0;
  o.bearing_rate_hz = 3.0;
  BearingRunSpec spec;
  spec.duration_s = 30.0;
  spec.world_T_robot_start = Pose2d(0.3, -1.2, 0.4);
  spec.wheel_speeds = [](double t) {
    return WheelSpeeds{0.05 + 0.04 * std::sin(0.3 * t), 0.05 + 0.03 * std::cos(0.7 * t)};
  };
  o.runs = {spec};
  BearingSimTruth truth;
  const BearingLog log = SimulateBearingLog(o, &truth);
  const BearingRun& run = log.runs[0];
  const std::vector<Pose2d>& poses = truth.runs[0].world_T_robot_at_bearings;
  const BearingMetricParams& m = o.truth;
  for (size_t i = 0; i < run.bearings.size(); i += 7) {
    for (size_t j = i; j < run.bearings.size(); j += 11) {
      const Pose2d motion =
          IntegrateEncoders(run.odometry, run.bearings[i].t_s, run.bearings[j].t_s, 0.3, 0.5,
                            m.delta_r, m.delta_l, m.delta_b);
      const Pose2d expected = Between(poses[i], poses[j]);
      EXPECT_NEAR((motion - expected).head<2>().norm(), 0.0, 1e-10);
      ExpectAngleNear(motion(2), expected(2), 1e-10);
      const Pose2d back = IntegrateEncoders(run.odometry, run.bearings[j].t_s, run.bearings[i].t_s,
                                            0.3, 0.5, m.delta_r, m.delta_l, m.delta_b);
      EXPECT_NEAR((Compose(motion, back)).norm(), 0.0, 1e-10);
    }
  }
}

TEST(BearingModelTest, EncoderCovarianceMatchesMonteCarlo) {
  std::mt19937 rng(5);
  const std::vector<EncoderSample> clean = WigglyOdometry(60, 0.1, &rng);
  const double r = 0.3, b = 0.5, k = 0.01, dr = 0.99, dl = 1.006, db = 0.97;
  const double t0 = 0.05, t1 = 5.5;
  const Eigen::Matrix3d cov = EncoderDisplacementCovariance(clean, t0, t1, r, b, dr, dl, db, k, k);
  const Pose2d mean = IntegrateEncoders(clean, t0, t1, r, b, dr, dl, db);
  std::normal_distribution<double> unit(0.0, 1.0);
  Eigen::Matrix3d sample = Eigen::Matrix3d::Zero();
  const int trials = 4000;
  for (int n = 0; n < trials; ++n) {
    std::vector<EncoderSample> noisy = clean;
    double left_noise = 0.0, right_noise = 0.0;
    for (size_t i = 1; i < clean.size(); ++i) {
      const double d_left = clean[i].left_rad - clean[i - 1].left_rad;
      const double d_right = clean[i].right_rad - clean[i - 1].right_rad;
      left_noise += std::sqrt(k * k / r * std::abs(d_left)) * unit(rng);
      right_noise += std::sqrt(k * k / r * std::abs(d_right)) * unit(rng);
      noisy[i].left_rad += left_noise;
      noisy[i].right_rad += right_noise;
    }
    Pose2d e = IntegrateEncoders(noisy, t0, t1, r, b, dr, dl, db) - mean;
    e(2) = WrapAngle(e(2));
    sample += e * e.transpose() / trials;
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(sample(i, i) / cov(i, i), 1.0, 0.1) << "axis " << i;
  }
  // Off-diagonals through the correlation coefficients.
  for (int i = 0; i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) {
      EXPECT_NEAR(sample(i, j) / std::sqrt(sample(i, i) * sample(j, j)),
                  cov(i, j) / std::sqrt(cov(i, i) * cov(j, j)), 0.06);
    }
  }
}

}  // namespace
}  // namespace calib
