#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_dead_reckoning.h>
#include <calib/solvers/laser/laser_refinement.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>

namespace calib {
namespace {

LaserCalibration Truth(const LaserSimOptions& options) {
  return LaserCalibration{options.odometry, options.base_T_sensor};
}

// Each parameter within `k` reported sigmas of the truth.
void ExpectWithinSigmas(const LaserCalibrationResult& result, const LaserCalibration& truth,
                        double k) {
  const LaserParamVector error = result.estimate.ToVector() - truth.ToVector();
  for (int i = 0; i < kNumLaserParams; ++i) {
    EXPECT_LT(std::abs(error(i)), k * result.stddev(i))
        << kLaserParamNames[i] << ": error " << error(i) << ", sigma " << result.stddev(i);
  }
}

TEST(CalibrateLaserTest, RefinementFromNominalValuesRecoversTheTruth) {
  LaserSimOptions sim;
  sim.num_intervals = 400;
  sim.speed_time_constant_s = 0.0;  // Constant speeds per interval: the model is exact.
  sim.scan_noise_sigma.setZero();
  const LaserLog log = SimulateLaserLog(sim);
  const LaserCalibration nominal{OdometryParams{0.021, 0.021, 0.09}, Pose2d(0.0, 0.0, -1.4)};
  LaserProblem problem({LaserDataset{&log.intervals, Eigen::Matrix3d::Identity() * 1e3}}, nominal,
                       LaserRefinementOptions{});
  ASSERT_TRUE(problem.Solve().ok());
  const LaserParamVector error = problem.calibration().ToVector() - Truth(sim).ToVector();
  EXPECT_LT(error.cwiseAbs().maxCoeff(), 1e-9) << error.transpose();
}

TEST(CalibrateLaserTest, NoiseFreeDataAreRecoveredExactly) {
  LaserSimOptions sim;
  sim.num_intervals = 300;
  sim.speed_time_constant_s = 0.0;
  sim.scan_noise_sigma.setZero();
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(SimulateLaserLog(sim).intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  const LaserParamVector error = result->estimate.ToVector() - Truth(sim).ToVector();
  EXPECT_LT(error.cwiseAbs().maxCoeff(), 1e-10) << error.transpose();
  EXPECT_EQ(result->inliers, result->samples);
}

// Wheel angles logged in degrees fit as well as in radians (the radii absorb the 57.3): only
// the size of the radius gives it away, and the result says so. In radians, no such warning.
TEST(CalibrateLaserTest, WheelAnglesInDegreesAreNamed) {
  LaserSimOptions sim;
  sim.num_intervals = 600;
  sim.seed = 5;
  std::vector<LaserInterval> intervals = SimulateLaserLog(sim).intervals;
  const auto names_units = [](const LaserCalibrationResult& r) {
    for (const std::string& w : r.observability.warnings) {
      if (w.find("radians") != std::string::npos) return true;
    }
    return false;
  };
  const StatusOr<LaserCalibrationResult> radians = CalibrateLaser(intervals);
  ASSERT_TRUE(radians.ok()) << radians.message();
  EXPECT_FALSE(names_units(*radians));
  for (LaserInterval& interval : intervals) {
    interval.left_speed *= 180.0 / M_PI;
    interval.right_speed *= 180.0 / M_PI;
    for (WheelStep& step : interval.steps) {
      step.left_rad *= 180.0 / M_PI;
      step.right_rad *= 180.0 / M_PI;
    }
  }
  const StatusOr<LaserCalibrationResult> degrees = CalibrateLaser(intervals);
  ASSERT_TRUE(degrees.ok()) << degrees.message();
  EXPECT_NEAR(degrees->estimate.odometry.left_radius_m, sim.odometry.left_radius_m * M_PI / 180.0,
              5.0 * degrees->stddev(0));
  EXPECT_TRUE(names_units(*degrees));
}

TEST(CalibrateLaserTest, NoisyLogWithinThreeSigmas) {
  LaserSimOptions sim;
  sim.num_intervals = 2000;
  sim.seed = 11;
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(SimulateLaserLog(sim).intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  ExpectWithinSigmas(*result, Truth(sim), 3.0);
  // The estimated scan noise is the simulated one.
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(result->noise_sigma[0](j), sim.scan_noise_sigma(j), 0.1 * sim.scan_noise_sigma(j));
  }
  EXPECT_TRUE(result->observability.warnings.empty()) << result->observability.warnings.front();
}

TEST(CalibrateLaserTest, RobustToTenPercentSlipOutliers) {
  LaserSimOptions sim;
  sim.num_intervals = 2000;
  sim.outlier_fraction = 0.10;
  sim.seed = 12;
  LaserSimTruth truth;
  const LaserLog log = SimulateLaserLog(sim, &truth);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  ExpectWithinSigmas(*result, Truth(sim), 3.0);
  // Most flagged outliers are rejected, few inliers are lost.
  int caught = 0, outliers = 0;
  for (size_t k = 0; k < log.intervals.size(); ++k) {
    if (truth.is_outlier[k]) {
      ++outliers;
      caught += !result->is_inlier[0][k];
    }
  }
  EXPECT_GT(caught, 0.8 * outliers);
  EXPECT_GT(result->inliers, 0.85 * sim.num_intervals);
}

// At 10⁵ intervals with 20 % slip outliers the Cauchy fit alone is biased far beyond its σ (the
// slips' pull a²/‖r‖ does not shrink with N, σ does): d² = eᵀΣ⁻¹e in the hundreds. The default
// final passes under Tukey's biweight give the slips no pull: d² within χ²₆'s 99 % point.
TEST(CalibrateLaserTest, RedescendingPassesLeaveNoSlipBiasAtScale) {
  LaserSimOptions sim;
  sim.num_intervals = 100000;
  sim.outlier_fraction = 0.20;
  const LaserLog log = SimulateLaserLog(sim);
  const auto mahalanobis = [&](double redescending_scale) {
    LaserCalibrationOptions options;
    options.refinement.redescending_scale = redescending_scale;
    const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals, options);
    EXPECT_TRUE(result.ok()) << result.message();
    if (!result.ok()) return 0.0;
    const LaserParamVector error = result->estimate.ToVector() - Truth(sim).ToVector();
    return error.dot(result->covariance.ldlt().solve(error));
  };
  EXPECT_GT(mahalanobis(0.0), 50.0);
  EXPECT_LT(mahalanobis(LaserRefinementOptions().redescending_scale), 16.8);
}

TEST(CalibrateLaserTest, LossNoneOnCleanDataHasUnitCovarianceScale) {
  LaserSimOptions sim;
  sim.num_intervals = 3000;
  sim.seed = 13;
  LaserCalibrationOptions options;
  options.refinement.loss = RobustLoss::kNone;
  options.noise_sigma = sim.scan_noise_sigma;
  const StatusOr<LaserCalibrationResult> result =
      CalibrateLaser(SimulateLaserLog(sim).intervals, options);
  ASSERT_TRUE(result.ok()) << result.message();
  // κ = reduced χ², 1 ± √(2/n) for the true noise.
  EXPECT_NEAR(result->covariance_scale, 1.0, 0.08);
}

// Over many seeds the reported 1σ and 2σ intervals hold the truth about 68 % and 95 % of the
// time: the error bars are honest.
TEST(CalibrateLaserTest, ReportedSigmasAreHonest) {
  int inside_1 = 0, inside_2 = 0, total = 0;
  for (int seed = 100; seed < 180; ++seed) {
    LaserSimOptions sim;
    sim.num_intervals = 1500;
    sim.seed = seed;
    sim.outlier_fraction = 0.02;
    const StatusOr<LaserCalibrationResult> result = CalibrateLaser(SimulateLaserLog(sim).intervals);
    ASSERT_TRUE(result.ok()) << result.message();
    const LaserParamVector z =
        (result->estimate.ToVector() - Truth(sim).ToVector()).cwiseQuotient(result->stddev);
    for (int i = 0; i < kNumLaserParams; ++i) {
      inside_1 += std::abs(z(i)) < 1.0;
      inside_2 += std::abs(z(i)) < 2.0;
      ++total;
    }
  }
  EXPECT_NEAR(static_cast<double>(inside_1) / total, 0.683, 0.08);
  EXPECT_GT(static_cast<double>(inside_2) / total, 0.91);
  EXPECT_LT(static_cast<double>(inside_2) / total, 0.99);
}

// The scalar loss correction of Ceres' covariance agrees with the full sandwich.
TEST(CalibrateLaserTest, CovarianceMatchesTheSandwich) {
  LaserSimOptions sim;
  sim.num_intervals = 2000;
  sim.outlier_fraction = 0.05;
  sim.seed = 14;
  const LaserLog log = SimulateLaserLog(sim);
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  LaserDataset dataset{&log.intervals, Eigen::Matrix3d::Identity()};
  dataset.sqrt_information = result->noise_sigma[0].cwiseInverse().asDiagonal();
  LaserProblem problem({dataset}, result->estimate, LaserRefinementOptions{});
  ASSERT_TRUE(problem.Solve().ok());
  const StatusOr<CorrectedCovariance<LaserParamMatrix>> scaled = problem.Covariance();
  const StatusOr<CorrectedCovariance<LaserParamMatrix>> sandwich = problem.SandwichCovariance();
  ASSERT_TRUE(scaled.ok() && sandwich.ok());
  EXPECT_EQ(sandwich->kappa, 1.0);
  for (int i = 0; i < kNumLaserParams; ++i) {
    EXPECT_NEAR(std::sqrt(scaled->covariance(i, i) / sandwich->covariance(i, i)), 1.0, 0.1)
        << kLaserParamNames[i];
  }
}

TEST(CalibrateLaserTest, JointLogsShareParametersAndKeepTheirNoise) {
  LaserSimOptions a, b;
  a.num_intervals = b.num_intervals = 1000;
  a.seed = 21;
  b.seed = 22;
  b.scan_noise_sigma *= 3.0;
  const LaserLog log_a = SimulateLaserLog(a), log_b = SimulateLaserLog(b);
  const StatusOr<LaserCalibrationResult> joint =
      CalibrateLaserJoint({&log_a.intervals, &log_b.intervals});
  const StatusOr<LaserCalibrationResult> alone = CalibrateLaser(log_a.intervals);
  ASSERT_TRUE(joint.ok() && alone.ok());
  ExpectWithinSigmas(*joint, Truth(a), 3.0);
  EXPECT_NEAR(joint->noise_sigma[1](0) / joint->noise_sigma[0](0), 3.0, 0.4);
  EXPECT_EQ(joint->samples, 2000);
  for (int i = 0; i < kNumLaserParams; ++i) EXPECT_LT(joint->stddev(i), alone->stddev(i));
}

// Raw encoder and scan-matcher streams, integrated into intervals (speeds vary inside them),
// give the truth back.
TEST(CalibrateLaserTest, RawStreamsAreIntegratedAndCalibrated) {
  LaserSimOptions sim;
  sim.num_intervals = 2000;
  sim.seed = 31;
  sim.speed_time_constant_s = 0.3;
  const LaserStreams streams = SimulateLaserStreams(sim, /*encoder_rate_hz=*/100.0);
  const StatusOr<LaserLog> log =
      LaserLogFromStreams(streams.odometry, streams.sensor_poses, "simulated streams");
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_FALSE(log->intervals[10].steps.empty());
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log->intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  ExpectWithinSigmas(*result, Truth(sim), 3.0);
}

TEST(CalibrateLaserTest, DegenerateLogsGiveTheMissingMotion) {
  LaserSimOptions sim;
  sim.trajectory = LaserTrajectory::kPureRotation;
  StatusOr<LaserCalibrationResult> result = CalibrateLaser(SimulateLaserLog(sim).intervals);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.message().find("pure rotations"), std::string::npos) << result.message();
  sim.trajectory = LaserTrajectory::kStraight;
  result = CalibrateLaser(SimulateLaserLog(sim).intervals);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.message().find("never turns"), std::string::npos) << result.message();
  result = CalibrateLaser({});
  ASSERT_FALSE(result.ok());
}

TEST(CalibrateLaserTest, BadIntervalsAreNamed) {
  LaserSimOptions sim;
  sim.num_intervals = 50;
  LaserLog log = SimulateLaserLog(sim);
  log.intervals[7].sensor_motion(1) = NAN;
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.message().find("record 8"), std::string::npos) << result.message();
}

TEST(CalibrateLaserTest, SingleArcIsDegenerate) {
  LaserSimOptions sim;
  sim.trajectory = LaserTrajectory::kConstantArc;
  sim.num_intervals = 500;
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(SimulateLaserLog(sim).intervals);
  // One wheel-speed ratio cannot separate J21 from J22.
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.message().find("different wheel-speed ratios"), std::string::npos)
      << result.message();
}

// Few turns: the estimate exists, and the report says that the sensor position rests on little.
TEST(CalibrateLaserTest, ThinTurningWarns) {
  LaserSimOptions straight, rich;
  straight.trajectory = LaserTrajectory::kStraight;
  straight.num_intervals = 2000;
  rich.num_intervals = 40;
  rich.seed = 3;
  std::vector<LaserInterval> intervals = SimulateLaserLog(straight).intervals;
  const LaserLog turns = SimulateLaserLog(rich);
  intervals.insert(intervals.end(), turns.intervals.begin(), turns.intervals.end());
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  bool warned = false;
  for (const std::string& warning : result->observability.warnings) {
    warned |= warning.find("few intervals turn") != std::string::npos;
  }
  EXPECT_TRUE(warned);
}

bool HasWarning(const LaserCalibrationResult& result, const std::string& words) {
  for (const std::string& warning : result.observability.warnings) {
    if (warning.find(words) != std::string::npos) return true;
  }
  return false;
}

// A refinement cut short by its iteration limit says so (it is not accepted silently).
TEST(CalibrateLaserTest, NoConvergenceIsReported) {
  LaserSimOptions sim;
  sim.num_intervals = 500;
  sim.seed = 41;
  const LaserLog log = SimulateLaserLog(sim);
  const StatusOr<LaserCalibrationResult> full = CalibrateLaser(log.intervals);
  ASSERT_TRUE(full.ok()) << full.message();
  EXPECT_TRUE(full->converged);
  EXPECT_TRUE(full->warnings.empty());
  LaserCalibrationOptions options;
  options.noise_rounds = 1;  // One solve from the closed form, one step long.
  options.refinement.max_iterations = 1;
  const StatusOr<LaserCalibrationResult> cut = CalibrateLaser(log.intervals, options);
  ASSERT_TRUE(cut.ok()) << cut.message();
  EXPECT_FALSE(cut->converged);
  EXPECT_TRUE(HasWarning(*cut, "without converging"));
}

// No interval under the inlier cut: the scan noise is still a number, and a warning says why.
TEST(CalibrateLaserTest, NoInliersGiveAFiniteFlaggedNoise) {
  LaserSimOptions sim;
  sim.num_intervals = 300;
  sim.seed = 42;
  LaserCalibrationOptions options;
  options.inlier_chi2 = 0.0;
  const StatusOr<LaserCalibrationResult> result =
      CalibrateLaser(SimulateLaserLog(sim).intervals, options);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_EQ(result->inliers, 0);
  ASSERT_EQ(result->noise_sigma.size(), 1u);
  EXPECT_TRUE(result->noise_sigma[0].allFinite());
  EXPECT_TRUE((result->noise_sigma[0].array() > 0.0).all());
  EXPECT_TRUE(HasWarning(*result, "no interval agrees with the model"));
}

// When the trimming removes the only turns, the untrimmed closed form seeds the refinement and
// the result says so.
// A log whose only three turns have a sensor motion off by 5 cm: the trimming drops them.
std::vector<LaserInterval> ThreeBadTurns() {
  LaserSimOptions sim;
  sim.num_intervals = 300;
  sim.seed = 43;
  const LaserLog log = SimulateLaserLog(sim);
  std::vector<LaserInterval> intervals;
  int turns = 0;
  for (const LaserInterval& interval : log.intervals) {
    const LaserMotionCensus kind = CountLaserMotion({interval});
    if (kind.turning() == 0) {
      intervals.push_back(interval);
    } else if (turns < 3) {
      intervals.push_back(interval);
      intervals.back().sensor_motion(0) += 0.05;
      ++turns;
    }
  }
  return intervals;
}

TEST(CalibrateLaserTest, FailedTrimmingFallsBackWithAWarning) {
  const std::vector<LaserInterval> intervals = ThreeBadTurns();
  ASSERT_EQ(CountLaserMotion(intervals).turning(), 3);
  ASSERT_TRUE(CensiClosedForm(intervals).ok());
  ASSERT_FALSE(CensiClosedFormTrimmed(intervals).ok());
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_FALSE(result->seed_trimmed);
  EXPECT_TRUE(HasWarning(*result, "the trimmed closed form failed"));
}

// The closed forms one calibration hands on (closed_forms_done) give another calibration of the
// same log the same result, gross intervals and trimming warning included; given for another
// log (a different size), they are not used.
TEST(CalibrateLaserTest, HandedOnClosedFormsGiveTheSameResult) {
  LaserSimOptions sim;
  sim.num_intervals = 400;
  sim.outlier_fraction = 0.05;
  const LaserLog slips = SimulateLaserLog(sim);
  for (const std::vector<LaserInterval>& intervals : {slips.intervals, ThreeBadTurns()}) {
    LaserCalibrationOptions options;
    std::shared_ptr<const LaserCalibrationResult> handed;
    options.closed_forms_done = [&](const LaserCalibrationResult& r) {
      handed = std::make_shared<const LaserCalibrationResult>(r);
    };
    const StatusOr<LaserCalibrationResult> own = CalibrateLaser(intervals, options);
    ASSERT_TRUE(own.ok() && handed != nullptr) << own.message();
    LaserCalibrationOptions taking;
    taking.closed_forms = handed;
    const StatusOr<LaserCalibrationResult> taken = CalibrateLaser(intervals, taking);
    ASSERT_TRUE(taken.ok()) << taken.message();
    EXPECT_EQ(taken->estimate.ToVector(), own->estimate.ToVector());
    EXPECT_EQ(taken->covariance, own->covariance);
    EXPECT_EQ(taken->closed_form_trimmed.calibration.ToVector(),
              own->closed_form_trimmed.calibration.ToVector());
    EXPECT_EQ(taken->gross_note, own->gross_note);
    EXPECT_EQ(taken->seed_trimmed, own->seed_trimmed);
    EXPECT_EQ(taken->warnings, own->warnings);

    const std::vector<LaserInterval> shorter(intervals.begin(), intervals.end() - 1);
    const StatusOr<LaserCalibrationResult> fresh = CalibrateLaser(shorter);
    const StatusOr<LaserCalibrationResult> not_taken = CalibrateLaser(shorter, taking);
    ASSERT_TRUE(fresh.ok() && not_taken.ok());
    EXPECT_EQ(not_taken->estimate.ToVector(), fresh->estimate.ToVector());
  }
  EXPECT_FALSE(CalibrateLaser(ThreeBadTurns())->seed_trimmed);
}

// A calibration that stops at the convex stage (no redescending stage, the estimate only: the
// model screen's base fit) takes the handing calibration's first stage bit for bit; a stage that
// started elsewhere (another noise level) is not taken.
TEST(CalibrateLaserTest, HandedOnConvexStageIsTheSameFit) {
  LaserSimOptions sim;
  sim.num_intervals = 1500;
  sim.outlier_fraction = 0.05;
  const LaserLog log = SimulateLaserLog(sim);
  LaserCalibrationOptions options;
  std::shared_ptr<const LaserCalibrationResult> handed;
  int calls = 0;
  options.closed_forms_done = [&](const LaserCalibrationResult& r) {
    ++calls;
    handed = std::make_shared<const LaserCalibrationResult>(r);
  };
  const StatusOr<LaserCalibrationResult> own = CalibrateLaser(log.intervals, options);
  ASSERT_TRUE(own.ok() && handed != nullptr) << own.message();
  EXPECT_EQ(calls, 1);
  ASSERT_TRUE(handed->convex_stage.has_value());
  EXPECT_NE(handed->convex_stage->estimate.ToVector(), own->estimate.ToVector());  // Redescended.

  LaserCalibrationOptions stops;
  stops.refinement.redescending_scale = 0.0;
  stops.estimate_only = true;
  stops.refinement.num_threads = 1;  // The split sums do not depend on it.
  const StatusOr<LaserCalibrationResult> alone = CalibrateLaser(log.intervals, stops);
  stops.closed_forms = handed;
  const StatusOr<LaserCalibrationResult> taken = CalibrateLaser(log.intervals, stops);
  ASSERT_TRUE(alone.ok() && taken.ok());
  EXPECT_EQ(taken->estimate.ToVector(), alone->estimate.ToVector());
  EXPECT_EQ(taken->iterations, alone->iterations);
  EXPECT_EQ(taken->noise_sigma, alone->noise_sigma);
  // Awaited once the log is checked, the same.
  int awaited = 0;
  LaserCalibrationOptions awaiting = stops;
  awaiting.closed_forms = nullptr;
  awaiting.await_closed_forms = [&] {
    ++awaited;
    return handed;
  };
  const StatusOr<LaserCalibrationResult> after_wait = CalibrateLaser(log.intervals, awaiting);
  ASSERT_TRUE(after_wait.ok());
  EXPECT_EQ(after_wait->estimate.ToVector(), alone->estimate.ToVector());
  EXPECT_EQ(awaited, 1);
  // Taken, not solved again: a stage altered after the fact shows in the result.
  auto altered = std::make_shared<LaserCalibrationResult>(*handed);
  altered->convex_stage->estimate.odometry.wheelbase_m *= 1.01;
  stops.closed_forms = altered;
  const StatusOr<LaserCalibrationResult> from_altered = CalibrateLaser(log.intervals, stops);
  ASSERT_TRUE(from_altered.ok());
  EXPECT_NE(from_altered->estimate.ToVector(), alone->estimate.ToVector());
  stops.closed_forms = handed;

  // Whitened otherwise, the stage does not apply: the fit is the calibration's own.
  stops.noise_sigma = Eigen::Vector3d(0.01, 0.01, 0.002);
  const StatusOr<LaserCalibrationResult> other = CalibrateLaser(log.intervals, stops);
  stops.closed_forms = nullptr;
  const StatusOr<LaserCalibrationResult> other_alone = CalibrateLaser(log.intervals, stops);
  ASSERT_TRUE(other.ok() && other_alone.ok());
  EXPECT_EQ(other->estimate.ToVector(), other_alone->estimate.ToVector());
  EXPECT_NE(other->estimate.ToVector(), alone->estimate.ToVector());
}

// Intervals built in memory bypass the readers' bounds: an absurd value is an error naming the
// interval, never a CHECK inside Ceres; a single big glitch costs its interval.
TEST(CalibrateLaserTest, AbsurdValueInMemoryIsRefusedAndGlitchCostsOneInterval) {
  LaserSimOptions sim;
  sim.num_intervals = 300;
  std::vector<LaserInterval> intervals = SimulateLaserLog(sim).intervals;
  const StatusOr<LaserCalibrationResult> clean = CalibrateLaser(intervals);
  ASSERT_TRUE(clean.ok()) << clean.message();
  intervals[100].sensor_motion(2) = 5e307;
  const StatusOr<LaserCalibrationResult> absurd = CalibrateLaser(intervals);
  ASSERT_FALSE(absurd.ok());
  EXPECT_NE(absurd.message().find("101"), std::string::npos) << absurd.message();
  EXPECT_NE(absurd.message().find("beyond what any unit explains"), std::string::npos)
      << absurd.message();
  intervals[100].sensor_motion(2) = 0.0;
  intervals[100].left_speed = 500.0;
  const StatusOr<LaserCalibrationResult> glitch = CalibrateLaser(intervals);
  ASSERT_TRUE(glitch.ok()) << glitch.message();
  EXPECT_EQ(glitch->gross_intervals, 1);
  for (int i = 0; i < kNumLaserParams; ++i) {
    EXPECT_NEAR(glitch->estimate.ToVector()(i), clean->estimate.ToVector()(i),
                0.5 * clean->stddev(i))
        << kLaserParamNames[i];
  }
  EXPECT_TRUE(glitch->unreliable.empty());
}

// The diagnosis whitens its effect fits by the base fit's robust noise level without computing it
// again: it must be exactly that of every interval's error at the estimate.
TEST(CalibrateLaserTest, RobustNoiseLevelIsThatOfTheEstimate) {
  LaserSimOptions sim;
  sim.num_intervals = 800;
  sim.outlier_fraction = 0.1;
  const LaserLog log = SimulateLaserLog(sim);
  for (const double redescending_scale : {0.0, LaserRefinementOptions{}.redescending_scale}) {
    LaserCalibrationOptions options;
    options.interval_jitter = false;
    options.estimate_only = true;
    options.refinement.redescending_scale = redescending_scale;
    const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals, options);
    ASSERT_TRUE(result.ok()) << result.message();
    ASSERT_EQ(result->robust_noise_sigma.size(), 1u);
    const Eigen::Vector3d direct =
        RobustNoiseSigma(LaserIntervalErrors(log.intervals, result->estimate));
    EXPECT_EQ(result->robust_noise_sigma[0], direct) << redescending_scale;
  }
}

}  // namespace
}  // namespace calib
