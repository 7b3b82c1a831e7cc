// The interval-jitter model of tuple/CSV logs: sensitivities against numeric differences, σ_j
// recovered within its σ on logs whose boundary stamps were jittered, no false alarms on clean
// ones.
#include <calib/core/laser/laser_simulator.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/timing/interval_jitter.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "tests/solvers/timing/jittered_log.h"

namespace calib {
namespace {

LaserCalibration Truth(const LaserSimOptions& options) {
  return LaserCalibration{options.odometry, options.base_T_sensor};
}

// A simulated log of `n` intervals whose boundary stamps scatter by `jitter_s`, estimated at the
// truth with every interval an inlier.
struct JitteredCase {
  JitteredCase(int n, uint64_t seed, double jitter_s) {
    sim.num_intervals = n;
    sim.seed = seed;
    log = JitteredTupleLog(sim, jitter_s);
  }
  IntervalJitterEstimate Estimate(const IntervalJitterOptions& options = {}) const {
    return EstimateIntervalJitter(log.intervals, Truth(sim), sim.scan_noise_sigma,
                                  std::vector<bool>(log.intervals.size(), true), options);
  }
  LaserSimOptions sim;
  LaserLog log;
};

// On a constant arc the end speeds are the interval's: moving the end by δ appends φ·δ of arc,
// moving the start removes it.
TEST(IntervalJitterTest, SensitivitiesAreTheDerivativesInTime) {
  LaserSimOptions sim;
  sim.trajectory = LaserTrajectory::kConstantArc;
  sim.num_intervals = 5;
  sim.scan_noise_sigma.setZero();
  const LaserLog log = SimulateLaserLog(sim);
  const LaserCalibration truth = Truth(sim);
  const std::vector<IntervalTimeSensitivity> g = IntervalTimeSensitivities(log.intervals, truth);
  const LaserParamVector p = truth.ToVector();
  const double h = 1e-6;
  for (size_t k = 0; k < log.intervals.size(); ++k) {
    LaserInterval longer = log.intervals[k], shorter = log.intervals[k];
    longer.duration_s += h;
    shorter.duration_s -= h;
    // e = ŝ − ŝ_pred: ŝ_pred moves by −de, and ŝ_pred(T + δ) is ŝ with the end moved by δ.
    const Eigen::Vector3d numeric = -(LaserResidual::Error(longer, p.data(), p.data() + 3) -
                                      LaserResidual::Error(shorter, p.data(), p.data() + 3)) /
                                    (2 * h);
    EXPECT_LT((g[k].end - numeric).norm(), 1e-7 * numeric.norm()) << k;
    EXPECT_LT((g[k].start + numeric).norm(), 1e-7 * numeric.norm()) << k;
  }
}

// On any log, stepped intervals included: moving an end by ε composes the motion of the wheel
// speeds there (BoundaryWheelSpeeds) onto that end; the sensitivities are its central differences.
TEST(IntervalJitterTest, SensitivitiesDifferentiateTheShiftedEnds) {
  LaserSimOptions sim;
  sim.num_intervals = 60;
  sim.record_steps = 3;
  sim.base_T_sensor = Pose2d(0.12, -0.05, 2.5);
  LaserLog log = SimulateLaserLog(sim);
  for (size_t k = 0; k < log.intervals.size(); k += 3) log.intervals[k].steps.clear();
  log.intervals[30].gap_before = true;
  const LaserCalibration truth = Truth(sim);
  const OdometryParams& o = truth.odometry;
  const std::vector<IntervalTimeSensitivity> g = IntervalTimeSensitivities(log.intervals, truth);
  const std::vector<IntervalBoundarySpeeds> speeds = BoundaryWheelSpeeds(log.intervals);
  const auto shifted = [&](size_t k, double eps_s, double eps_e) {
    const Pose2d before =
        WheelStepDisplacement(o.left_radius_m, o.right_radius_m, o.wheelbase_m,
                              -speeds[k].start(0) * eps_s, -speeds[k].start(1) * eps_s);
    const Pose2d after = WheelStepDisplacement(o.left_radius_m, o.right_radius_m, o.wheelbase_m,
                                               speeds[k].end(0) * eps_e, speeds[k].end(1) * eps_e);
    const Pose2d motion =
        IntervalRobotMotion(o.left_radius_m, o.right_radius_m, o.wheelbase_m, log.intervals[k]);
    return SensorMotionFromRobotMotion(truth.base_T_sensor,
                                       Compose(Compose(before, motion), after));
  };
  const double h = 1e-6;
  for (size_t k = 0; k < log.intervals.size(); ++k) {
    const Eigen::Vector3d end = (shifted(k, 0, h) - shifted(k, 0, -h)) / (2 * h);
    const Eigen::Vector3d start = (shifted(k, h, 0) - shifted(k, -h, 0)) / (2 * h);
    EXPECT_LT((g[k].end - end).norm(), 1e-7 * (1.0 + end.norm())) << k;
    EXPECT_LT((g[k].start - start).norm(), 1e-7 * (1.0 + start.norm())) << k;
  }
}

TEST(IntervalJitterTest, BoundarySpeedsInterpolateTheNeighbours) {
  std::vector<LaserInterval> intervals(3);
  intervals[0].duration_s = 1.0, intervals[0].left_speed = 1.0, intervals[0].right_speed = 2.0;
  intervals[1].duration_s = 3.0, intervals[1].left_speed = 5.0, intervals[1].right_speed = 2.0;
  intervals[2].duration_s = 1.0, intervals[2].left_speed = 0.0, intervals[2].right_speed = 0.0;
  intervals[2].gap_before = true;
  const std::vector<IntervalBoundarySpeeds> speeds = BoundaryWheelSpeeds(intervals);
  // Centres at 0.5 and 2.5, boundary at 1: a quarter of the way from the first to the second.
  EXPECT_NEAR(speeds[0].end(0), 2.0, 1e-12);
  EXPECT_NEAR(speeds[1].start(1), 2.0, 1e-12);
  EXPECT_NEAR(speeds[0].start(0), 1.0, 1e-12);
  EXPECT_NEAR(speeds[1].end(0), 5.0, 1e-12);  // A gap follows: its own speed.
  EXPECT_NEAR(speeds[2].start(0), 0.0, 1e-12);
}

TEST(IntervalJitterTest, SqrtInformationWhitensTheCovariance) {
  IntervalTimeSensitivity g;
  g.start = Eigen::Vector3d(1e-3, 2e-3, -4e-3);
  g.end = Eigen::Vector3d(-2e-3, 1e-3, 5e-3);
  const Eigen::Vector3d noise(1e-3, 2e-3, 3e-3);
  const Eigen::Matrix3d l = JitterSqrtInformation({g}, noise, 0.5).front();
  const Eigen::Matrix3d sigma =
      Eigen::Matrix3d(noise.cwiseAbs2().asDiagonal()) + JitterCovariance(g, 0.5);
  EXPECT_LT((l * sigma * l.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-9);
}

// The refit's inlier test takes eᵀΣ⁻¹e by cofactors: ‖L·e‖² with the root's L, and the
// sensitivities from given boundary speeds, or of a sample, are those computed from the intervals.
TEST(IntervalJitterTest, WhitenedNormsAreTheRootsNorms) {
  const JitteredCase jittered(300, 11, 0.02);
  const LaserCalibration truth = Truth(jittered.sim);
  const std::vector<LaserInterval>& intervals = jittered.log.intervals;
  const std::vector<IntervalTimeSensitivity> g = IntervalTimeSensitivities(intervals, truth);
  const std::vector<IntervalTimeSensitivity> given =
      IntervalTimeSensitivities(intervals, BoundaryWheelSpeeds(intervals), truth);
  ASSERT_EQ(given.size(), g.size());
  for (size_t k = 0; k < g.size(); ++k) {
    EXPECT_TRUE(given[k].start == g[k].start && given[k].end == g[k].end) << k;
  }
  // A sample's sensitivities, from its intervals' own boundary speeds, are the full ones: at the
  // log's ends and on both sides of a gap too.
  std::vector<LaserInterval> gapped = intervals;
  gapped[150].gap_before = true;
  const std::vector<IntervalTimeSensitivity> full = IntervalTimeSensitivities(gapped, truth);
  const std::vector<size_t> sample = {0, 7, 149, 150, 151, gapped.size() - 1};
  const std::vector<IntervalTimeSensitivity> sampled =
      IntervalTimeSensitivities(gapped, truth, sample);
  ASSERT_EQ(sampled.size(), sample.size());
  for (size_t i = 0; i < sample.size(); ++i) {
    EXPECT_TRUE(sampled[i].start == full[sample[i]].start && sampled[i].end == full[sample[i]].end)
        << sample[i];
  }
  const LaserParamVector p = truth.ToVector();
  std::vector<Eigen::Vector3d> errors;
  for (const LaserInterval& interval : intervals) {
    errors.push_back(LaserResidual::Error(interval, p.data(), p.data() + 3));
  }
  for (const double jitter_s : {0.0, 0.02}) {
    const std::vector<double> norms =
        JitterWhitenedSquaredNorms(errors, g, jittered.sim.scan_noise_sigma, jitter_s);
    const std::vector<Eigen::Matrix3d> roots =
        JitterSqrtInformation(g, jittered.sim.scan_noise_sigma, jitter_s);
    ASSERT_EQ(norms.size(), errors.size());
    for (size_t k = 0; k < errors.size(); ++k) {
      const double expected = (roots[k] * errors[k]).squaredNorm();
      EXPECT_NEAR(norms[k], expected, 1e-12 * expected) << k << " at " << jitter_s;
    }
  }
  // A zero noise level and no jitter: Σ singular, the root's answer (no division by zero hidden).
  const std::vector<double> singular = JitterWhitenedSquaredNorms(
      {Eigen::Vector3d(1.0, 0.0, 0.0)}, {g[0]}, Eigen::Vector3d::Zero(), 0.0);
  const double root_norm =
      (JitterSqrtInformation({g[0]}, Eigen::Vector3d::Zero(), 0.0)[0] * Eigen::Vector3d::UnitX())
          .squaredNorm();
  EXPECT_TRUE(singular[0] == root_norm || (std::isnan(singular[0]) && std::isnan(root_norm)));
}

TEST(IntervalJitterTest, RecoversTheJitterWithinItsSigma) {
  const double jitter_s = 0.03;
  const JitteredCase jittered(2000, 5, jitter_s);
  const LaserSimOptions& sim = jittered.sim;
  const IntervalJitterEstimate estimate = jittered.Estimate();
  EXPECT_TRUE(estimate.significant) << estimate.p_value;
  EXPECT_LT(std::abs(estimate.jitter_s - jitter_s), 3 * estimate.jitter_stddev_s)
      << estimate.jitter_s << " ± " << estimate.jitter_stddev_s;
  EXPECT_LT(estimate.jitter_stddev_s, 0.2 * jitter_s);
  // The scan noise is not inflated by the jitter: it stays the simulated one.
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(estimate.noise_sigma(j), sim.scan_noise_sigma(j), 0.1 * sim.scan_noise_sigma(j));
  }
}

// A previous round's estimate narrows the search without moving the answer (beyond 1e-3 of its σ);
// one far from the maximum (its bracket's edge) falls back to the grid.
TEST(IntervalJitterTest, PreviousEstimateGivesTheGridsAnswer) {
  const JitteredCase jittered(2000, 6, 0.03);
  const IntervalJitterEstimate grid = jittered.Estimate();
  for (double previous : {0.8 * grid.jitter_s, 1.5 * grid.jitter_s, 20.0 * grid.jitter_s}) {
    IntervalJitterOptions options;
    options.previous_jitter_s = previous;
    const IntervalJitterEstimate near = jittered.Estimate(options);
    EXPECT_NEAR(near.jitter_s, grid.jitter_s, 1e-3 * grid.jitter_stddev_s) << previous;
    EXPECT_NEAR(near.jitter_stddev_s, grid.jitter_stddev_s, 1e-2 * grid.jitter_stddev_s);
    EXPECT_NEAR(near.log_likelihood, grid.log_likelihood, 1e-6);
  }
}

// A previous round's noise levels start the joint scoring in place of a profile at the previous
// σ_j: the same maximum, from levels 10 % off as from the profile's own.
TEST(IntervalJitterTest, PreviousNoiseLevelsStartTheJointScoringAtTheSameMaximum) {
  const JitteredCase jittered(2000, 6, 0.03);
  IntervalJitterOptions profiled;
  profiled.previous_jitter_s = 0.8 * jittered.Estimate().jitter_s;
  const IntervalJitterEstimate reference = jittered.Estimate(profiled);
  ASSERT_TRUE(reference.significant);
  for (double off : {0.9, 1.0, 1.1}) {
    IntervalJitterOptions started = profiled;
    started.previous_noise_sigma = off * reference.noise_sigma;
    const IntervalJitterEstimate e = jittered.Estimate(started);
    EXPECT_NEAR(e.jitter_s, reference.jitter_s, 1e-6 * reference.jitter_s) << off;
    EXPECT_LT((e.noise_sigma - reference.noise_sigma)
                  .cwiseQuotient(reference.noise_sigma)
                  .cwiseAbs()
                  .maxCoeff(),
              1e-6);
    EXPECT_NEAR(e.log_likelihood, reference.log_likelihood, 1e-8);
    EXPECT_NEAR(e.jitter_stddev_s, reference.jitter_stddev_s, 1e-4 * reference.jitter_stddev_s);
  }
}

// σ of σ_j is computed only where asked (a refit's last round): the rest of the estimate is the
// same bit for bit, and the predicate sees the estimate it decides on.
TEST(IntervalJitterTest, StddevOnlyWhereWanted) {
  const JitteredCase jittered(1000, 7, 0.02);
  const IntervalJitterEstimate always = jittered.Estimate();
  ASSERT_TRUE(always.significant);
  for (bool wanted : {false, true}) {
    IntervalJitterOptions options;
    double seen_jitter_s = 0.0;
    options.stddev_wanted = [&](const IntervalJitterEstimate& e) {
      seen_jitter_s = e.jitter_s;
      return wanted;
    };
    const IntervalJitterEstimate e = jittered.Estimate(options);
    EXPECT_EQ(seen_jitter_s, always.jitter_s);
    EXPECT_EQ(e.jitter_s, always.jitter_s);
    EXPECT_EQ(e.noise_sigma, always.noise_sigma);
    EXPECT_EQ(e.log_likelihood, always.log_likelihood);
    EXPECT_EQ(e.p_value, always.p_value);
    if (wanted) {
      EXPECT_EQ(e.jitter_stddev_s, always.jitter_stddev_s);
    } else {
      EXPECT_TRUE(std::isnan(e.jitter_stddev_s));
    }
  }
}

// Joint scoring in (θ, σ_j²) lands where the golden-section search of the profile does, from the
// grid and from a previous round's estimate.
TEST(IntervalJitterTest, JointScoringGivesTheProfileSearchsAnswer) {
  const JitteredCase jittered(2000, 8, 0.02);
  for (double previous : {0.0, 0.015}) {
    IntervalJitterOptions golden, joint;
    golden.joint_scoring = false;
    golden.previous_jitter_s = joint.previous_jitter_s = previous;
    const IntervalJitterEstimate a = jittered.Estimate(golden);
    const IntervalJitterEstimate b = jittered.Estimate(joint);
    ASSERT_TRUE(a.significant && b.significant);
    EXPECT_NEAR(b.jitter_s, a.jitter_s, 1e-3 * a.jitter_stddev_s) << previous;
    // σ of σ_j: the observed information's against the search's difference quotient of the
    // profile over ±10 % of σ_j (a curvature O(h²) off: within 1 %).
    EXPECT_NEAR(b.jitter_stddev_s, a.jitter_stddev_s, 1e-2 * a.jitter_stddev_s);
    EXPECT_LT((b.noise_sigma - a.noise_sigma).cwiseQuotient(a.noise_sigma).cwiseAbs().maxCoeff(),
              1e-4);
    // The joint maximum is the profile's: no lower than the search's.
    EXPECT_GE(b.log_likelihood, a.log_likelihood - 1e-7);
  }
}

// At the fitted parameters of clean logs the test rejects σ_j = 0 at about its level.
TEST(IntervalJitterTest, FewFalseAlarmsOnCleanLogs) {
  int alarms = 0;
  const int seeds = 40;
  for (int seed = 1; seed <= seeds; ++seed) {
    LaserSimOptions sim;
    sim.num_intervals = 400;
    sim.seed = 100 + seed;
    const LaserLog log = SimulateLaserLog(sim);
    LaserCalibrationOptions options;
    options.interval_jitter = false;
    const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals, options);
    ASSERT_TRUE(result.ok()) << result.message();
    IntervalJitterOptions jitter_options;
    jitter_options.significance = 0.05;
    const IntervalJitterEstimate estimate =
        EstimateIntervalJitter(log.intervals, result->estimate, result->noise_sigma[0],
                               result->is_inlier[0], jitter_options);
    alarms += estimate.significant;
  }
  // 5 % of 40 is 2; more than 6 has probability below 1 % under the nominal level.
  EXPECT_LE(alarms, 6);
}

}  // namespace
}  // namespace calib
