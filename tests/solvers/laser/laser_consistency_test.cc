// The timing-free consistency check: exact on noise-free data, honest σ on clean noisy data, and a
// warning when the calibration is biased (a wrong wheelbase, stamps that are not sample times).
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/random.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_consistency.h>
#include <calib/solvers/laser/laser_consistency_terms.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace calib {
namespace {

const OdometryParams kOdometry{0.0206, 0.0207, 0.088};
const Pose2d kMounting(-0.005, 0.006, -1.55);
const Eigen::Vector3d kNoise(0.001, 0.001, 0.002);

// A robot that turns mostly left (net rotation of many turns, as a real robot driving loops):
// constant wheel speeds within each interval, held for a few intervals, with a rest of three
// intervals every `rest_every` (0: never). Scan noise kNoise·noise_scale.
std::vector<LaserInterval> DriveLoops(int n, uint64_t seed, double noise_scale, int rest_every) {
  Random random(seed);
  std::vector<LaserInterval> intervals(n);
  Eigen::Vector2d speed = Eigen::Vector2d::Zero();
  for (int k = 0; k < n; ++k) {
    LaserInterval& in = intervals[k];
    in.start_s = k > 0 ? intervals[k - 1].start_s + intervals[k - 1].duration_s : 0.0;
    in.duration_s = random.Uniform(0.7, 0.9);
    if (k % 4 == 0) {
      speed << random.Uniform(-0.3, 0.5), random.Uniform(-0.2, 0.6);
    }
    const bool rest = rest_every > 0 && k % rest_every < 3;
    in.left_speed = rest ? 0.0 : speed(0);
    in.right_speed = rest ? 0.0 : speed(1);
    const Pose2d robot = WheelStepDisplacement(kOdometry.left_radius_m, kOdometry.right_radius_m,
                                               kOdometry.wheelbase_m, in.left_speed * in.duration_s,
                                               in.right_speed * in.duration_s);
    in.sensor_motion = SensorMotionFromRobotMotion(kMounting, robot);
    for (int j = 0; j < 3; ++j) in.sensor_motion(j) += noise_scale * kNoise(j) * random.Normal();
    in.record = k + 1;
  }
  return intervals;
}

// Stamps that are not sample times: the wheel rotation attributed to each interval runs from
// t_k + ε_k to t_{k+1} + ε_{k+1}, ε of σ `jitter_s`; the sensor saw the true intervals. The
// increments only move between neighbours, so every total inside the log is unchanged.
std::vector<LaserInterval> ShiftWheelIncrements(std::vector<LaserInterval> intervals,
                                                double jitter_s, uint64_t seed) {
  Random random(seed);
  std::vector<Eigen::Vector2d> moved(intervals.size() + 1, Eigen::Vector2d::Zero());
  for (size_t k = 1; k < intervals.size(); ++k) {
    const Eigen::Vector2d rate(intervals[k - 1].left_speed + intervals[k].left_speed,
                               intervals[k - 1].right_speed + intervals[k].right_speed);
    const bool rest = intervals[k - 1].left_speed == 0.0 || intervals[k].left_speed == 0.0;
    moved[k] = rest ? Eigen::Vector2d::Zero()
                    : Eigen::Vector2d(rate / 2.0 * jitter_s *
                                      random.Normal());  // From interval k to interval k − 1.
  }
  for (size_t k = 0; k < intervals.size(); ++k) {
    LaserInterval& in = intervals[k];
    const Eigen::Vector2d shift = moved[k + 1] - moved[k];
    in.left_speed += shift(0) / in.duration_s;
    in.right_speed += shift(1) / in.duration_s;
  }
  return intervals;
}

LaserConsistency Check(const std::vector<LaserInterval>& intervals,
                       const LaserCalibrationResult& result, const LaserCalibration& estimate,
                       const LaserConsistencyOptions& options = {}) {
  return CheckLaserConsistency(intervals, estimate, result.covariance, result.noise_sigma[0],
                               result.is_inlier[0], options);
}

TEST(LaserConsistencyTest, NoiseFreeSimulationAgreesExactly) {
  LaserSimOptions options;
  options.scan_noise_sigma.setZero();
  options.num_intervals = 500;
  const LaserLog log = SimulateLaserLog(options);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  const LaserConsistency& check = result->consistency;
  ASSERT_TRUE(check.checked) << check.note;
  ASSERT_FALSE(check.windows.empty());
  EXPECT_TRUE(check.warnings.empty());
  for (const LaserConsistencyWindow& w : check.windows) {
    // Rotation is linear in the wheel rotation; the travel's arc length holds within an interval
    // whose curvature changes up to the second order of that change.
    EXPECT_NEAR(w.rotation.measured, w.rotation.predicted, 1e-9);
    EXPECT_NEAR(w.translation.measured, w.translation.predicted, 1e-7);
    EXPECT_GT(std::abs(w.rotation.measured), 0.1);
  }
}

// Clean noisy simulations: no warning, and z ~ N(0, 1) when the stamps are known to be sample
// times (no end timing); the end timing only widens σ.
TEST(LaserConsistencyTest, CleanLogsDoNotWarnAndZIsStandardNormal) {
  const int seeds = 120;
  int warned = 0;
  double sum[2] = {0, 0}, sum_sq[2] = {0, 0}, sum_sq_default[2] = {0, 0};
  for (int seed = 1; seed <= seeds; ++seed) {
    LaserSimOptions options;
    options.seed = seed;
    options.num_intervals = 500;
    const LaserLog log = SimulateLaserLog(options);
    const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
    ASSERT_TRUE(result.ok()) << result.message();
    warned += !result->consistency.warnings.empty();
    LaserConsistencyOptions no_ends;
    no_ends.end_timing_fraction = 0.0;
    const LaserConsistency check = Check(log.intervals, *result, result->estimate, no_ends);
    ASSERT_TRUE(check.checked) << check.note;
    const LaserConsistencyWindow& run = check.windows.front();
    const LaserConsistencyWindow& run_default = result->consistency.windows.front();
    EXPECT_EQ(run.kind, "run");
    const double z[2] = {run.rotation.z, run.translation.z};
    const double z_default[2] = {run_default.rotation.z, run_default.translation.z};
    for (int i = 0; i < 2; ++i) {
      sum[i] += z[i];
      sum_sq[i] += z[i] * z[i];
      sum_sq_default[i] += z_default[i] * z_default[i];
    }
  }
  EXPECT_LE(warned, 2) << "false alarms over " << seeds << " clean logs";
  for (int i = 0; i < 2; ++i) {
    const double mean = sum[i] / seeds;
    const double sd = std::sqrt(sum_sq[i] / seeds - mean * mean);
    EXPECT_NEAR(mean, 0.0, 0.3) << (i == 0 ? "rotation" : "translation");
    EXPECT_GT(sd, 0.8) << (i == 0 ? "rotation" : "translation");
    EXPECT_LT(sd, 1.2) << (i == 0 ? "rotation" : "translation");
    EXPECT_LE(sum_sq_default[i], sum_sq[i] * 1.001);  // Ends only add variance.
  }
}

// Raw streams: poses from a scan matcher telescope (sm_k = p_k⁻¹ p_{k+1}); no false alarm.
TEST(LaserConsistencyTest, StreamsWithTelescopingPosesDoNotWarn) {
  for (int seed = 1; seed <= 10; ++seed) {
    LaserSimOptions options;
    options.seed = seed;
    options.num_intervals = 600;
    const LaserStreams streams = SimulateLaserStreams(options, 50.0);
    const StatusOr<LaserLog> log = LaserLogFromStreams(streams.odometry, streams.sensor_poses, "s");
    ASSERT_TRUE(log.ok()) << log.message();
    const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log->intervals);
    ASSERT_TRUE(result.ok()) << result.message();
    EXPECT_TRUE(result->consistency.checked);
    EXPECT_TRUE(result->consistency.warnings.empty()) << result->consistency.warnings[0];
  }
}

// A wheelbase 3 % too large turns the predicted rotation down by 3 %; with the radii scaled with
// it (what a fit with b held off gives: r/b keeps the rotation), the travel is too long (10 %: the
// net travel of this log is short).
// b held fixed: its zero variance in the covariance.
TEST(LaserConsistencyTest, WrongWheelbaseWarns) {
  const std::vector<LaserInterval> intervals = DriveLoops(600, 7, 1.0, 100);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_TRUE(result->consistency.warnings.empty()) << result->consistency.warnings[0];
  LaserCalibrationResult fixed_b = *result;
  fixed_b.covariance.row(kLaserB).setZero();
  fixed_b.covariance.col(kLaserB).setZero();

  LaserCalibration wrong_b = result->estimate;
  wrong_b.odometry.wheelbase_m *= 1.03;
  const LaserConsistency rotation = Check(intervals, fixed_b, wrong_b);
  ASSERT_FALSE(rotation.warnings.empty());
  EXPECT_TRUE(rotation.windows.front().rotation.significant);
  EXPECT_NE(rotation.warnings.front().find("of rotation over t = 0.0–"), std::string::npos)
      << rotation.warnings.front();
  EXPECT_NE(rotation.warnings.front().find("timing"), std::string::npos);

  LaserCalibration scaled = result->estimate;
  scaled.odometry.wheelbase_m *= 1.10;
  scaled.odometry.left_radius_m *= 1.10;
  scaled.odometry.right_radius_m *= 1.10;
  const LaserConsistency travel = Check(intervals, fixed_b, scaled);
  EXPECT_TRUE(travel.windows.front().translation.significant)
      << travel.windows.front().translation.z << " " << travel.windows.front().translation.predicted
      << " " << travel.windows.front().translation.measured << " "
      << travel.windows.front().translation.sigma;
  EXPECT_FALSE(travel.windows.front().rotation.significant);
}

// Stamps that are not sample times (a logger picking samples up to ~a period late): the wheel
// totals are those of the truth, the per-interval fit is biased (errors in the regressors), and
// the check says so.
TEST(LaserConsistencyTest, TimingErrorWarnsWhileTotalsKeepTheTruth) {
  int warned = 0;
  for (int seed = 1; seed <= 3; ++seed) {
    const std::vector<LaserInterval> clean = DriveLoops(600, seed, 1.0, 100);
    const std::vector<LaserInterval> shifted = ShiftWheelIncrements(clean, 0.3, seed + 100);
    Eigen::Vector2d clean_total = Eigen::Vector2d::Zero(), shifted_total = clean_total;
    for (size_t k = 0; k < clean.size(); ++k) {
      clean_total +=
          Eigen::Vector2d(clean[k].left_speed, clean[k].right_speed) * clean[k].duration_s;
      shifted_total +=
          Eigen::Vector2d(shifted[k].left_speed, shifted[k].right_speed) * shifted[k].duration_s;
    }
    EXPECT_LT((clean_total - shifted_total).norm(), 1e-9);
    // Stamps taken as sample times (CalibrateLaser's boundary-jitter treatment off).
    LaserCalibrationOptions stamps_as_truth;
    stamps_as_truth.interval_jitter = false;
    const StatusOr<LaserCalibrationResult> result = CalibrateLaser(shifted, stamps_as_truth);
    ASSERT_TRUE(result.ok()) << result.message();
    EXPECT_GT(std::abs(result->estimate.odometry.left_radius_m / kOdometry.left_radius_m - 1.0),
              0.1);                                   // The fit is biased...
    warned += !result->consistency.warnings.empty();  // ...and the check sees it.
  }
  EXPECT_EQ(warned, 3);
}

// Rests split a run into windows; a rest at both ends removes the end timing.
TEST(LaserConsistencyTest, WindowsBetweenRestsHaveNoEndTiming) {
  const std::vector<LaserInterval> intervals = DriveLoops(400, 3, 1.0, 100);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  const LaserConsistency& check = result->consistency;
  int between = 0;
  for (const LaserConsistencyWindow& w : check.windows) {
    if (w.kind != "between rests") continue;
    ++between;
    EXPECT_EQ(w.first % 100, 3);
    EXPECT_LT(w.rotation.sigma_ends, 1e-12);
    EXPECT_LT(w.translation.sigma_ends, 1e-12);
  }
  EXPECT_GE(between, 2);
  EXPECT_EQ(check.tests, 2 * static_cast<int>(check.windows.size()));
}

// Short windows go side by side on the threads, long ones split their sums: the same figures,
// bit for bit and in the same order, as on one thread.
TEST(LaserConsistencyTest, WindowsOnTwoThreadsEqualOneThread) {
  const std::vector<LaserInterval> intervals = DriveLoops(6000, 5, 1.0, 300);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  LaserConsistencyOptions one, two;
  one.num_threads = 1;
  two.num_threads = 2;
  const LaserConsistency a = Check(intervals, *result, result->estimate, one);
  const LaserConsistency b = Check(intervals, *result, result->estimate, two);
  ASSERT_EQ(a.windows.size(), b.windows.size());
  EXPECT_GE(a.windows.size(), 15u);  // The run and the stretches between its rests.
  for (size_t i = 0; i < a.windows.size(); ++i) {
    EXPECT_EQ(a.windows[i].kind, b.windows[i].kind);
    EXPECT_EQ(a.windows[i].first, b.windows[i].first);
    for (const auto& [x, y] : {std::pair(a.windows[i].rotation, b.windows[i].rotation),
                               std::pair(a.windows[i].translation, b.windows[i].translation)}) {
      EXPECT_EQ(x.measured, y.measured) << i;
      EXPECT_EQ(x.sigma, y.sigma) << i;
      EXPECT_EQ(x.z, y.z) << i;
    }
  }
  EXPECT_EQ(a.warnings, b.warnings);
}

TEST(LaserConsistencyTest, ForwardTravelIsTheArcLength) {
  const Pose2d arc = ArcDisplacement(0.3, 0.8);
  const Pose2d sm = SensorMotionFromRobotMotion(kMounting, arc);
  EXPECT_NEAR(consistency_internal::ForwardTravel(sm, kMounting), 0.3, 1e-12);
  EXPECT_NEAR(consistency_internal::ForwardTravel(
                  SensorMotionFromRobotMotion(kMounting, ArcDisplacement(-0.2, 0.0)), kMounting),
              -0.2, 1e-12);
}

// ∂travel/∂ℓ in closed form against central differences, turning both ways and near straight.
TEST(LaserConsistencyTest, ForwardTravelGradientMatchesNumericDifferences) {
  const Pose2d mounting(0.12, -0.05, 2.3);
  for (const double turn : {0.7, -1.9, 3e-5, 0.0}) {
    const Pose2d sm = SensorMotionFromRobotMotion(mounting, ArcDisplacement(0.25, turn));
    Eigen::Vector3d gradient;
    const double travel = consistency_internal::ForwardTravel(sm, mounting, &gradient);
    EXPECT_NEAR(travel, 0.25, 1e-12) << turn;
    for (int i = 0; i < 3; ++i) {
      constexpr double kStep = 1e-6;
      Pose2d plus = mounting, minus = mounting;
      plus(i) += kStep;
      minus(i) -= kStep;
      const double numeric = (consistency_internal::ForwardTravel(sm, plus) -
                              consistency_internal::ForwardTravel(sm, minus)) /
                             (2.0 * kStep);
      EXPECT_NEAR(gradient(i), numeric, 1e-8) << "turn " << turn << ", parameter " << i;
    }
  }
}

// The published recordings (tuples: independent scan matches). Reports what it sees; see the
// closing note for l90/lmov.
// The running Bartlett sums equal the direct ones, zeros beyond the sequence included.
TEST(LaserConsistencyTest, RunningBartlettSumsEqualDirectSums) {
  Random random(5);
  std::vector<double> x(200);
  for (double& v : x) v = random.Uniform(-1.0, 1.0);
  const auto x_at = [&](long i) {
    return i >= 0 && i < static_cast<long>(x.size()) ? x[static_cast<size_t>(i)] : 0.0;
  };
  for (const int lag : {1, 3, 17}) {
    const long k0 = 5;
    consistency_internal::BartlettCentred<double, decltype(x_at)> centred(x_at, lag, k0);
    consistency_internal::BartlettAhead<double, decltype(x_at)> ahead(x_at, lag, k0);
    for (long k = k0; k < 210; ++k, centred.Advance(), ahead.Advance()) {
      double direct_centred = 0.0, direct_ahead = 0.0;
      for (long j = -lag; j <= lag; ++j) {
        const double w = 1.0 - static_cast<double>(std::abs(j)) / (lag + 1);
        direct_centred += w * x_at(k + j);
        if (j > 0) direct_ahead += w * x_at(k + j);
      }
      ASSERT_NEAR(centred.value(), direct_centred, 1e-12) << "lag " << lag << " k " << k;
      ASSERT_NEAR(ahead.value(), direct_ahead, 1e-12) << "lag " << lag << " k " << k;
    }
  }
}

// The scores' long-run covariance at several lags in one chunked pass equals the direct sum
// Σ_k Σ_{|j|≤L} w_j g_k g_{k+j}ᵀ at each lag, on a log split into several chunks.
TEST(LaserConsistencyTest, ScoreLongRunEqualsDirectSums) {
  Random random(8);
  consistency_internal::LogTerms log;
  log.terms.resize(2600);
  for (auto& t : log.terms) {
    for (int i = 0; i < kNumLaserParams; ++i) t.score(i) = static_cast<float>(random.Normal());
  }
  const long n = static_cast<long>(log.terms.size());
  const std::vector<int> lags = {1, 4, 23};
  const std::vector<LaserParamMatrix> fast = consistency_internal::ScoreLongRun({log}, lags, 2);
  ASSERT_EQ(fast.size(), lags.size());
  for (size_t l = 0; l < lags.size(); ++l) {
    LaserParamMatrix direct = LaserParamMatrix::Zero();
    for (long k = 0; k < n; ++k) {
      for (long j = -lags[l]; j <= lags[l]; ++j) {
        if (k + j < 0 || k + j >= n) continue;
        const double w = 1.0 - static_cast<double>(std::abs(j)) / (lags[l] + 1);
        direct += w * log.terms[k].Score() * log.terms[k + j].Score().transpose();
      }
    }
    EXPECT_LT((fast[l] - direct).norm(), 1e-10 * direct.norm()) << "lag " << lags[l];
  }
}

TEST(LaserConsistencyTest, CensiTupleLogs) {
  const std::string dir = CALIB_CENSI_DATA_DIR;
  if (!std::filesystem::exists(dir + "/l90.tuple")) GTEST_SKIP() << "no recordings at " << dir;
  for (const char* name : {"l90", "lmov", "lstraight"}) {
    const StatusOr<LaserLog> log = ReadLaserLog(dir + "/" + name + ".tuple");
    ASSERT_TRUE(log.ok()) << log.message();
    const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log->intervals);
    ASSERT_TRUE(result.ok()) << result.message();
    const LaserConsistency& check = result->consistency;
    ASSERT_TRUE(check.checked) << check.note;
    const LaserConsistencyWindow& run = check.windows.front();
    std::printf("%s: rotation %.1f° vs %.1f° (z %.1f), travel %.3f m vs %.3f m (z %.1f)\n", name,
                run.rotation.predicted * 180 / M_PI, run.rotation.measured * 180 / M_PI,
                run.rotation.z, run.translation.predicted, run.translation.measured,
                run.translation.z);
    // Rotation agrees within its σ on every set.
    EXPECT_FALSE(run.rotation.significant) << name;
  }
}

}  // namespace
}  // namespace calib
