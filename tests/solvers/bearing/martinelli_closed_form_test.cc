#include <calib/core/bearing/bearing_log_io.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/solvers/bearing/bearing_bundle_adjustment.h>
#include <calib/solvers/bearing/martinelli_closed_form.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>

#include "tests/scratch_dir.h"

namespace calib {
namespace {

void ExpectAngleNear(double a, double b, double tol) { EXPECT_NEAR(WrapAngle(a - b), 0.0, tol); }

void ExpectRelNear(double a, double b, double tol) {
  EXPECT_NEAR(a / b, 1.0, tol) << a << " vs " << b;
}

// Distance of x from the nearest point of {y + j·step}.
double ModDistance(double x, double y, double step) {
  const double d = std::fmod(std::abs(x - y), step);
  return std::min(d, step - d);
}

BearingSimOptions NoiseFree() {
  BearingSimOptions o;
  o.encoder_noise_k = 0.0;
  o.bearing_noise_rad = 0.0;
  return o;
}

// Angles (the first two entries) within tol, the others within tol relative.
template <typename Vector>
void ExpectParamVectorNear(const Vector& a, const Vector& t, double tol) {
  for (int i = 0; i < a.size(); ++i) {
    if (i < 2) {
      ExpectAngleNear(a(i), t(i), tol);
    } else {
      ExpectRelNear(a(i), t(i), tol);
    }
  }
}

void ExpectParamsNear(const BearingParams& p, const BearingParams& t, double tol) {
  ExpectParamVectorNear(ToVector(p), ToVector(t), tol);
}

void ExpectMetricNear(const BearingMetricParams& m, const BearingMetricParams& t, double tol) {
  ExpectParamVectorNear(ToVector(m), ToVector(t), tol);
}

std::string Fails(const BearingLog& log, const MartinelliOptions& options = {}) {
  const StatusOr<MartinelliEstimate> e = MartinelliClosedForm(log, options);
  return e.ok() ? "" : e.message();
}

// ---------------------------------------------------------------------------------------------
// Exact recovery on noise-free circles.

TEST(MartinelliClosedFormTest, NoiseFreeSection81RecoversEverything) {
  BearingSimOptions o = NoiseFree();
  o.initial_distance_run = 2;
  BearingSimTruth truth;
  const BearingLog log = SimulateBearingLog(o, &truth);
  const StatusOr<MartinelliEstimate> e = MartinelliClosedForm(log);
  ASSERT_TRUE(e.ok()) << e.message();
  ExpectParamsNear(e->params, truth.params, 1e-9);
  EXPECT_NEAR(e->eta_x_per_m, truth.params.eta_per_m * std::cos(truth.params.phi_rad), 1e-9);
  EXPECT_NEAR(e->eta_y_per_m, truth.params.eta_per_m * std::sin(truth.params.phi_rad), 1e-9);
  ASSERT_TRUE(e->has_metric);
  ExpectMetricNear(e->metric, truth.metric, 1e-9);
  ASSERT_EQ(e->runs.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const MartinelliRunEstimate& run = e->runs[i];
    const BearingRunTruth& t = truth.runs[i];
    const double period = 2 * M_PI / std::abs(t.xi_q_per_m);
    EXPECT_NEAR(run.q, t.q, 1e-12);
    ExpectRelNear(run.xi_q_per_m, t.xi_q_per_m, 1e-10);
    EXPECT_GT(run.periods_covered, 0.95);
    EXPECT_LT(run.rms_residual_rad, 1e-10);
    // Nodes repeat every half period; L on its defined branch; k, c as eqs. 17 and 21.
    EXPECT_LT(ModDistance(run.node_m, t.circle.node_m, 0.5 * period), 1e-9 * period);
    EXPECT_NEAR(run.l_rad, t.state0.L, 1e-9);
    ExpectRelNear(run.k_per_m, t.k_per_m, 1e-9);
    EXPECT_NEAR(run.c_rad, t.c_rad, 1e-9);
    EXPECT_NEAR(run.a0, t.state0.A, 1e-8 * (1 + std::abs(t.state0.A)));
    EXPECT_NEAR(run.v0, t.state0.V, 1e-8 * (1 + std::abs(t.state0.V)));
    ExpectRelNear(run.mu0, t.mu0, 1e-9);
    ExpectAngleNear(run.gamma0_rad, t.gamma0_rad, 1e-9);
    // c and S_w put a node of eq. 26 on the node found, and c is one of eq. 26's candidates.
    EXPECT_LT(
        ModDistance(NodeFromC(run.c_rad, run.xi_q_per_m, run.s_w, 0), run.node_m, 0.5 * period),
        1e-9 * period);
    EXPECT_NEAR(run.c_rad, run.c_candidates_rad[run.s_w == 1 ? 0 : 1], 1e-9);
    // Algorithm 1 (linear interpolation of 1 Hz bearings) and eq. 36 are close, not exact.
    EXPECT_LT(ModDistance(run.node_algorithm1_m, t.circle.node_m, 0.5 * period), 1e-4 * period);
    EXPECT_LT(run.spread_algorithm1_rad, 2e-3);
    EXPECT_NEAR(run.l_algorithm1_rad, t.state0.L, 2e-4);
    EXPECT_NEAR(run.k_mirror_points_per_m / t.k_per_m, 1.0, 5e-3);
  }
}

TEST(MartinelliClosedFormTest, AlgorithmOneAndEq36PathIsCloseOnNoiseFreeData) {
  BearingSimOptions o = NoiseFree();
  o.bearing_rate_hz = 10.0;
  o.initial_distance_run = 1;
  BearingSimTruth truth;
  const BearingLog log = SimulateBearingLog(o, &truth);
  MartinelliOptions options;
  options.refine_with_all_samples = false;
  const StatusOr<MartinelliEstimate> e = MartinelliClosedForm(log, options);
  ASSERT_TRUE(e.ok()) << e.message();
  // Only linear interpolation limits it.
  EXPECT_NEAR(e->params.phi_rad, truth.params.phi_rad, 2e-3);
  EXPECT_NEAR(e->params.psi_rad, truth.params.psi_rad, 2e-3);
  EXPECT_NEAR(e->params.eta_per_m / truth.params.eta_per_m, 1.0, 5e-3);
  ExpectRelNear(e->params.delta, truth.params.delta, 1e-9);  // From the periods alone.
  ExpectRelNear(e->params.xi_per_m, truth.params.xi_per_m, 1e-9);
  EXPECT_NEAR(e->metric.rho_m / truth.metric.rho_m, 1.0, 2e-2);
}

struct RandomCase {
  BearingSimOptions options;
  BearingSimTruth truth;
  BearingLog log;
};

// Random parameters, 3–5 runs with distinct q (some clockwise: q > 1/δ), random starts, 1–2
// loops, bearings at 1–5 Hz with a third of them dropped at random (uneven in s). Geometries
// where the sensor grazes the landmark (|r| near 1) or barely sees it move are redrawn.
RandomCase MakeRandomCase(std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(*rng); };
  while (true) {
    RandomCase c;
    BearingSimOptions& o = c.options;
    o = NoiseFree();
    o.truth = BearingMetricParams{uniform(-1.2, 1.2), uniform(0.1, 0.4), uniform(-M_PI, M_PI),
                                  uniform(0.9, 1.1),  uniform(0.9, 1.1), uniform(0.9, 1.1)};
    o.wheelbase_m = uniform(0.3, 0.6);
    o.bearing_rate_hz = uniform(1.0, 5.0);
    std::vector<double> qs = {uniform(0.5, 0.9), uniform(-0.3, 0.3), uniform(-1.2, -0.8),
                              uniform(1.3, 2.0), uniform(-3.0, -2.0)};
    std::shuffle(qs.begin(), qs.end(), *rng);
    const int runs = 3 + static_cast<int>(unit(*rng) * 3);
    bool good = true;
    for (int i = 0; i < runs; ++i) {
      BearingRunSpec spec;
      spec.q = qs[i];
      spec.loops = uniform(1.0, 2.0);
      const double d = uniform(0.6, 2.0), a = uniform(-M_PI, M_PI);
      spec.world_T_robot_start = Pose2d(d * std::cos(a), d * std::sin(a), uniform(-M_PI, M_PI));
      const BearingCircle circle =
          CircleFromStart(o.truth, o.wheelbase_m, spec.q, spec.world_T_robot_start);
      const double r = std::abs(circle.ratio);
      good &= std::abs(r - 1.0) > 0.25 && std::min(r, 1.0 / r) > 0.1;
      o.runs.push_back(spec);
    }
    if (!good) continue;
    o.initial_distance_run = 1 + static_cast<int>(unit(*rng) * runs);
    c.log = SimulateBearingLog(o, &c.truth);
    for (BearingRun& run : c.log.runs) {
      std::vector<BearingSample> kept;
      for (const BearingSample& b : run.bearings) {
        if (unit(*rng) > 0.33) kept.push_back(b);
      }
      run.bearings = kept;
    }
    return c;
  }
}

TEST(MartinelliClosedFormTest, NoiseFreeRandomGeometriesRecoverEverything) {
  std::mt19937 rng(11);
  for (int i = 0; i < 12; ++i) {
    const RandomCase c = MakeRandomCase(&rng);
    const StatusOr<MartinelliEstimate> e = MartinelliClosedForm(c.log);
    ASSERT_TRUE(e.ok()) << "case " << i << ": " << e.message();
    SCOPED_TRACE("case " + std::to_string(i));
    ExpectParamsNear(e->params, c.truth.params, 1e-7);
    ExpectMetricNear(e->metric, c.truth.metric, 1e-7);
    for (size_t j = 0; j < e->runs.size(); ++j) {
      ExpectRelNear(e->runs[j].xi_q_per_m, c.truth.runs[j].xi_q_per_m, 1e-9);
      EXPECT_NEAR(e->runs[j].l_rad, c.truth.runs[j].state0.L, 1e-7);
      ExpectRelNear(e->runs[j].k_per_m, c.truth.runs[j].k_per_m, 1e-7);
    }
  }
}

TEST(MartinelliClosedFormTest, GapsInTheBearingsAreFine) {
  // A narrow field of view: each run loses the bearings of 35% of its loop (two runs over 1.5
  // loops so that the bearings still span a period).
  BearingSimOptions o = NoiseFree();
  o.runs = MartinelliRuns(Pose2d(-0.2, -0.8, 0.5));
  o.runs[0].loops = o.runs[1].loops = 1.5;
  o.initial_distance_run = 1;
  BearingSimTruth truth;
  BearingLog log = SimulateBearingLog(o, &truth);
  for (BearingRun& run : log.runs) {
    const double t0 = run.odometry.front().t_s, t1 = run.odometry.back().t_s;
    std::vector<BearingSample> kept;
    for (const BearingSample& b : run.bearings) {
      const double f = std::fmod((b.t_s - t0) / (t1 - t0) * (run.id == 3 ? 1.0 : 1.5), 1.0);
      if (f < 0.4 || f > 0.75) kept.push_back(b);
    }
    run.bearings = kept;
  }
  const StatusOr<MartinelliEstimate> e = MartinelliClosedForm(log);
  ASSERT_TRUE(e.ok()) << e.message();
  ExpectParamsNear(e->params, truth.params, 1e-8);
  ExpectMetricNear(e->metric, truth.metric, 1e-8);
}

TEST(MartinelliClosedFormTest, PureSpinRunCarriesTheScale) {
  // q = −1/δ turns on the spot: ηq = 0 makes eq. 13's Ψ1 infinite, so μ0, γ0 of that run come
  // from the landmark's placement instead of inverting eqs. 13 and 15.
  BearingSimOptions o = NoiseFree();
  o.truth.phi_rad = 0.3;
  o.truth.psi_rad = -2.0;
  o.runs = MartinelliRuns(Pose2d(0.4, -1.1, 0.3));
  o.runs[2].q = -o.truth.delta_r / o.truth.delta_l;
  o.initial_distance_run = 3;
  BearingSimTruth truth;
  const StatusOr<MartinelliEstimate> e = MartinelliClosedForm(SimulateBearingLog(o, &truth));
  ASSERT_TRUE(e.ok()) << e.message();
  ExpectParamsNear(e->params, truth.params, 1e-8);
  ExpectMetricNear(e->metric, truth.metric, 1e-8);
}

TEST(MartinelliClosedFormTest, SameAnswerThroughTheFileFormat) {
  BearingSimOptions o;
  o.bearing_noise_rad = M_PI / 180;
  o.initial_distance_run = 2;
  const BearingLog log = SimulateBearingLog(o);
  const testing::ScratchDir scratch("martinelli_roundtrip_");
  const std::string dir = scratch.path().string();
  ASSERT_TRUE(WriteBearingLog(log, dir).ok());
  const StatusOr<BearingLog> read = ReadBearingLog(dir);
  ASSERT_TRUE(read.ok()) << read.message();
  const StatusOr<MartinelliEstimate> a = MartinelliClosedForm(log);
  const StatusOr<MartinelliEstimate> b = MartinelliClosedForm(*read);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->params.phi_rad, b->params.phi_rad);
  EXPECT_EQ(a->params.xi_per_m, b->params.xi_per_m);
  EXPECT_EQ(a->metric.rho_m, b->metric.rho_m);
}

// ---------------------------------------------------------------------------------------------
// The steps.

TEST(MartinelliClosedFormTest, NoisyMonteCarloStaysNearTheInformationLimit) {
  // §8.1 with σβ = 1°, K = 0.001 m^½, landmark 1 m to the left of the start. Bounds are ~2× the
  // mean errors seen over 20 runs; see the report for the comparison with Table 4.
  double sums[6] = {0, 0, 0, 0, 0, 0};
  const int n = 10;
  for (int i = 0; i < n; ++i) {
    BearingSimOptions o;
    o.bearing_noise_rad = M_PI / 180;
    o.initial_distance_run = 2;
    o.seed = 500 + i;
    BearingSimTruth truth;
    const StatusOr<MartinelliEstimate> e = MartinelliClosedForm(SimulateBearingLog(o, &truth));
    ASSERT_TRUE(e.ok()) << e.message();
    const BearingParams& p = e->params;
    const BearingParams& t = truth.params;
    sums[0] += std::abs(WrapAngle(p.phi_rad - t.phi_rad)) * 180 / M_PI / n;
    sums[1] += std::abs(WrapAngle(p.psi_rad - t.psi_rad)) * 180 / M_PI / n;
    sums[2] += std::abs(p.eta_per_m / t.eta_per_m - 1) / n;
    sums[3] += std::abs(p.delta / t.delta - 1) / n;
    sums[4] += std::abs(p.xi_per_m / t.xi_per_m - 1) / n;
    sums[5] += std::abs(e->metric.rho_m / truth.metric.rho_m - 1) / n;
  }
  EXPECT_LT(sums[0], 2.0);
  EXPECT_LT(sums[1], 2.0);
  EXPECT_LT(sums[2], 0.05);
  EXPECT_LT(sums[3], 8e-4);
  EXPECT_LT(sums[4], 4e-3);
  EXPECT_LT(sums[5], 0.03);
}

// ---------------------------------------------------------------------------------------------
// Degenerate input: a status that says what is missing.

TEST(MartinelliClosedFormDegenerateTest, FewerThanThreeDistinctQ) {
  BearingSimOptions o = NoiseFree();
  o.runs = MartinelliRuns();
  o.runs[2].q = 0.02;  // Same as run 2 within min_q_separation.
  const std::string message = Fails(SimulateBearingLog(o));
  EXPECT_NE(message.find("at least 3 distinct"), std::string::npos) << message;
  EXPECT_NE(message.find("found 2"), std::string::npos) << message;
  o.runs.pop_back();
  EXPECT_NE(Fails(SimulateBearingLog(o)).find("at least 3 distinct"), std::string::npos);
}

TEST(MartinelliClosedFormDegenerateTest, LessThanAPeriod) {
  BearingSimOptions o = NoiseFree();
  o.runs = MartinelliRuns();
  o.runs[1].loops = 0.6;
  const std::string message = Fails(SimulateBearingLog(o));
  EXPECT_NE(message.find("run 2"), std::string::npos) << message;
  EXPECT_NE(message.find("of a period"), std::string::npos) << message;
}

TEST(MartinelliClosedFormDegenerateTest, LandmarkDirectionBarelyChanges) {
  for (const Pose2d& start : {Pose2d(0.0, -500.0, 0.0),  // Far away: β is the robot's turn.
                              Pose2d(0.0, -0.3 * 1.65 / 2.0412371134, 0.0)}) {  // Centre.
    BearingSimOptions o = NoiseFree();
    o.runs = MartinelliRuns();
    o.runs[1].world_T_robot_start = start;
    const std::string message = Fails(SimulateBearingLog(o));
    EXPECT_NE(message.find("run 2"), std::string::npos) << message;
    EXPECT_NE(message.find("barely changes"), std::string::npos) << message;
  }
}

TEST(MartinelliClosedFormDegenerateTest, SensorOnTheAxleLine) {
  // φ = 90°: every centre of rotation lies on the sensor's line of sight along the axle, so L is
  // the same for all q and η is not observable from circles.
  BearingSimOptions o = NoiseFree();
  o.truth.phi_rad = M_PI / 2;
  const std::string message = Fails(SimulateBearingLog(o));
  EXPECT_NE(message.find("wheel axle"), std::string::npos) << message;
}

TEST(MartinelliClosedFormDegenerateTest, StraightRunHasNoPeriod) {
  BearingSimOptions o = NoiseFree();
  o.runs = MartinelliRuns();
  o.runs[0].q = 0.99 / 1.006;  // ξq = 0.
  o.runs[0].duration_s = 100.0;
  const std::string message = Fails(SimulateBearingLog(o));
  EXPECT_NE(message.find("run 1"), std::string::npos) << message;
}

TEST(MartinelliClosedFormDegenerateTest, NonCircularRunsAreRejectedOrSkipped) {
  BearingSimOptions o = NoiseFree();
  o.runs = MartinelliRuns();
  BearingRunSpec wiggle;
  wiggle.duration_s = 60.0;
  wiggle.wheel_speeds = [](double t) { return WheelSpeeds{0.05 + 0.03 * std::sin(0.2 * t), 0.05}; };
  o.runs.push_back(wiggle);
  BearingSimTruth truth;
  const BearingLog log = SimulateBearingLog(o, &truth);
  const StatusOr<MartinelliEstimate> rejected = MartinelliClosedForm(log);
  ASSERT_FALSE(rejected.ok());
  EXPECT_EQ(rejected.code(), StatusCode::kNotObservable);
  EXPECT_NE(rejected.message().find("run 4 is not a circle"), std::string::npos)
      << rejected.message();
  MartinelliOptions skip;
  skip.skip_non_circular_runs = true;
  const StatusOr<MartinelliEstimate> e = MartinelliClosedForm(log, skip);
  ASSERT_TRUE(e.ok()) << e.message();
  EXPECT_EQ(e->skipped_runs, std::vector<int>{4});
  ExpectParamsNear(e->params, truth.params, 1e-9);
  BearingLog with_distance = log;
  with_distance.meta.initial_distance = InitialDistance{4, 1.0};
  EXPECT_NE(Fails(with_distance, skip).find("not a circular run"), std::string::npos);
}

TEST(MartinelliClosedFormDegenerateTest, WheelsAndSamples) {
  BearingSimOptions o = NoiseFree();
  o.runs = MartinelliRuns();
  o.runs[2].wheel_speeds = [](double) { return WheelSpeeds{0.05, 0.0}; };
  o.runs[2].duration_s = 30.0;
  std::string message = Fails(SimulateBearingLog(o));
  EXPECT_NE(message.find("run 3: the right wheel does not turn"), std::string::npos) << message;
  o.runs[2].wheel_speeds = [](double) { return WheelSpeeds{0.05, 0.001}; };
  message = Fails(SimulateBearingLog(o));
  EXPECT_NE(message.find("run 3: the right wheel barely turns"), std::string::npos) << message;

  BearingSimOptions sparse = NoiseFree();
  sparse.bearing_rate_hz = 0.2;  // Six bearings in the 30 s loop at q = −1.
  message = Fails(SimulateBearingLog(sparse));
  EXPECT_NE(message.find("run 3"), std::string::npos) << message;
  EXPECT_NE(message.find("at least 8"), std::string::npos) << message;
}

TEST(MartinelliClosedFormDegenerateTest, InvalidLogsAreReported) {
  BearingLog log = SimulateBearingLog(NoiseFree());
  log.runs[0].bearings[5].bearing_rad = std::nan("");
  EXPECT_NE(Fails(log).find("not finite"), std::string::npos);
  log = SimulateBearingLog(NoiseFree());
  log.runs[1].bearings.clear();
  EXPECT_NE(Fails(log).find("run 2 has no bearings"), std::string::npos);
}

}  // namespace
}  // namespace calib
