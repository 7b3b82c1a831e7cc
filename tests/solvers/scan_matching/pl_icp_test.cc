#include <calib/core/scan/scan_simulator.h>
#include <calib/solvers/scan_matching/correspondences.h>
#include <calib/solvers/scan_matching/pl_icp.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <chrono>
#include <cstdio>
#include <limits>
#include <random>

#include "tests/solvers/scan_matching/test_scans.h"

namespace calib {
namespace {

using test_scans::CastScan;
using test_scans::ScanSpec;

const Pose2d kReferencePose(0.3, -0.2, 0.1);

double PoseError(const Pose2d& a, const Pose2d& b) {
  return std::max((a.head<2>() - b.head<2>()).norm(), std::abs(WrapAngle(a(2) - b(2))));
}

void ExpectExactRecovery(const ScanSpec& spec) {
  const auto room = test_scans::RoomWithBoxes();
  const LaserScan reference = CastScan(room, kReferencePose, spec);
  const std::vector<Pose2d> motions = {Pose2d(0.1, 0.05, 0.0), Pose2d(0.3, -0.2, 0.2),
                                       Pose2d(-0.25, 0.15, -0.3), Pose2d(0.05, 0.0, 0.35),
                                       Pose2d(0.0, 0.0, -0.18)};
  for (const Pose2d& truth : motions) {
    const LaserScan current = CastScan(room, Compose(kReferencePose, truth), spec);
    const Pose2d guess = truth + Pose2d(0.05, -0.04, 0.03);
    const StatusOr<ScanMatch> match = MatchScans(reference, current, guess);
    ASSERT_TRUE(match.ok()) << match.message();
    EXPECT_TRUE(match->ok()) << match->reason;
    EXPECT_LT(PoseError(match->reference_T_current, truth), 1e-6)
        << "truth " << truth.transpose() << " got " << match->reference_T_current.transpose();
    EXPECT_GT(match->correspondences, spec.beams / 2);
  }
}

TEST(PlIcpTest, RecoversTheDisplacementExactlyFromNoiseFreeScans360) {
  ExpectExactRecovery(ScanSpec{});
}

TEST(PlIcpTest, RecoversTheDisplacementExactlyFromNoiseFreeScans1081) {
  ScanSpec spec;
  spec.beams = 1081;
  spec.fov_rad = 1.5 * M_PI;
  ExpectExactRecovery(spec);
}

// With range noise the error, over many trials, is within the reported covariance: the
// normalised errors z = L⁻¹e (Σ = LLᵀ) have an RMS near one and stay within 3σ.
TEST(PlIcpTest, CovarianceIsHonestUnderRangeNoise) {
  const auto room = test_scans::RoomWithBoxes();
  ScanSpec spec;
  spec.range_sigma_m = 0.01;
  std::mt19937 rng(7);
  const Pose2d truth(0.2, -0.1, 0.15);
  double sum_z2 = 0.0;
  int within_3_sigma = 0;
  const int trials = 150;
  for (int trial = 0; trial < trials; ++trial) {
    const LaserScan reference = CastScan(room, kReferencePose, spec, &rng);
    const LaserScan current = CastScan(room, Compose(kReferencePose, truth), spec, &rng);
    const StatusOr<ScanMatch> match =
        MatchScans(reference, current, truth + Pose2d(0.03, 0.02, -0.02));
    ASSERT_TRUE(match.ok()) << match.message();
    ASSERT_TRUE(match->ok()) << match->reason;
    Eigen::Vector3d error = match->reference_T_current - truth;
    error(2) = WrapAngle(error(2));
    const Eigen::Vector3d z = match->covariance.llt().matrixL().solve(error);
    sum_z2 += z.squaredNorm();
    bool inside = true;
    for (int k = 0; k < 3; ++k)
      inside &= std::abs(error(k)) < 3.0 * std::sqrt(match->covariance(k, k));
    within_3_sigma += inside;
    EXPECT_NEAR(match->range_sigma_m, 0.01, 0.003);
  }
  const double rms_z = std::sqrt(sum_z2 / (3.0 * trials));
  std::printf("RMS normalised error over %d trials: %.3f; within 3 sigma: %d\n", trials, rms_z,
              within_3_sigma);
  EXPECT_GT(rms_z, 0.8);
  EXPECT_LT(rms_z, 1.25);
  EXPECT_GE(within_3_sigma, trials * 95 / 100);
}

// A 270° scan turned clockwise by 0.1 rad: its first beams look beyond the reference's field of
// view, and their nearest reference points are the reference's end beams, on surfaces it may not
// show there. Such pairs pulled the pose by about −0.3 mm in y and +0.2 mrad in θ on average
// (1081 beams, 1 cm noise, a bare room). And lines through a corner (points of both walls) pulled
// x by −0.32 mm (5 standard errors: the room's front corners are seen, its back ones are not).
// Both left out (the default), x, y and θ average to within 3 standard errors of zero.
TEST(PlIcpTest, ScanEndsAndCornersAreNoNearestPoints) {
  std::vector<test_scans::Wall> room;
  test_scans::AddBox(-5.0, -3.0, 5.0, 3.0, &room);
  room.push_back({{-4.0, 2.0}, {-2.5, 2.9}});
  ScanSpec spec;
  spec.beams = 1081;
  spec.fov_rad = 1.5 * M_PI;
  spec.range_sigma_m = 0.01;
  const Pose2d truth(0.02, 0.0, -0.1);
  const auto mean_error = [&](int scan_end_beams, double max_bend_rad,
                              Eigen::Vector3d* standard_error) {
    std::mt19937 rng(5);
    PlIcpOptions options;
    options.correspondence.scan_end_beams = scan_end_beams;
    options.correspondence.max_bend_rad = max_bend_rad;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
    const int trials = 200;
    for (int trial = 0; trial < trials; ++trial) {
      const LaserScan reference = CastScan(room, kReferencePose, spec, &rng);
      const LaserScan current = CastScan(room, Compose(kReferencePose, truth), spec, &rng);
      const StatusOr<ScanMatch> match =
          MatchScans(reference, current, truth + Pose2d(0.01, -0.01, 0.01), options);
      EXPECT_TRUE(match.ok() && match->ok());
      Eigen::Vector3d error = match->reference_T_current - truth;
      error(2) = WrapAngle(error(2));
      sum += error;
      sum2 += error.cwiseAbs2();
    }
    const Eigen::Vector3d mean = sum / trials;
    *standard_error = ((sum2 / trials - mean.cwiseAbs2()) / trials).cwiseSqrt();
    std::printf(
        "scan end beams %d, max bend %.1f rad: mean error %+.1f ± %.1f, %+.1f ± %.1f um, "
        "%+.1f ± %.1f urad\n",
        scan_end_beams, max_bend_rad, 1e6 * mean(0), 1e6 * (*standard_error)(0), 1e6 * mean(1),
        1e6 * (*standard_error)(1), 1e6 * mean(2), 1e6 * (*standard_error)(2));
    return mean;
  };
  const CorrespondenceOptions defaults;
  Eigen::Vector3d se_ends, se_corners, se;
  const Eigen::Vector3d ends_kept = mean_error(0, defaults.max_bend_rad, &se_ends);
  const Eigen::Vector3d corners_kept = mean_error(defaults.scan_end_beams, M_PI, &se_corners);
  const Eigen::Vector3d both_left_out =
      mean_error(defaults.scan_end_beams, defaults.max_bend_rad, &se);
  EXPECT_GT(std::abs(ends_kept(2)), 3.0 * se_ends(2));
  EXPECT_GT(std::abs(corners_kept(0)), 3.0 * se_corners(0));
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(both_left_out(i)), 3.0 * se(i)) << i;
}

TEST(PlIcpTest, FlagsACorridorAsDegenerate) {
  const auto corridor = test_scans::Corridor();
  ScanSpec spec;
  spec.range_max_m = 15.0;
  const LaserScan reference = CastScan(corridor, Pose2d(0, 0, 0), spec);
  const LaserScan current = CastScan(corridor, Pose2d(0.3, 0.1, 0.05), spec);
  const StatusOr<ScanMatch> match = MatchScans(reference, current, Pose2d(0.25, 0.12, 0.04));
  ASSERT_TRUE(match.ok()) << match.message();
  EXPECT_EQ(match->quality, ScanMatchQuality::kDegenerate) << match->reason;
  EXPECT_FALSE(match->reason.empty());
  // Across the corridor and in heading the match is still exact.
  EXPECT_NEAR(match->reference_T_current(1), 0.1, 1e-6);
  EXPECT_NEAR(match->reference_T_current(2), 0.05, 1e-6);
}

TEST(PlIcpTest, FlagsAScanWithTooFewReturns) {
  const auto room = test_scans::RoomWithBoxes();
  const LaserScan reference = CastScan(room, kReferencePose, ScanSpec{});
  LaserScan current = CastScan(room, kReferencePose, ScanSpec{});
  for (size_t i = 10; i < current.ranges_m.size(); ++i) current.ranges_m[i] = NAN;
  StatusOr<ScanMatch> match = MatchScans(reference, current, Pose2d::Zero());
  ASSERT_TRUE(match.ok()) << match.message();
  EXPECT_EQ(match->quality, ScanMatchQuality::kTooFewCorrespondences) << match->reason;
  EXPECT_TRUE(std::isinf(match->covariance(0, 0)));

  LaserScan empty = current;
  empty.ranges_m.clear();
  match = MatchScans(empty, reference, Pose2d::Zero());
  ASSERT_TRUE(match.ok()) << match.message();
  EXPECT_EQ(match->quality, ScanMatchQuality::kTooFewCorrespondences);
  match = MatchScans(reference, empty, Pose2d::Zero());
  ASSERT_TRUE(match.ok()) << match.message();
  EXPECT_EQ(match->quality, ScanMatchQuality::kTooFewCorrespondences);
}

TEST(PlIcpTest, FlagsAMatchFarFromItsGuessAsPoor) {
  const auto room = test_scans::RoomWithBoxes();
  const LaserScan reference = CastScan(room, kReferencePose, ScanSpec{});
  const LaserScan current = CastScan(room, Compose(kReferencePose, Pose2d(0, 0, 1.5)), ScanSpec{});
  const StatusOr<ScanMatch> match = MatchScans(reference, current, Pose2d::Zero());
  ASSERT_TRUE(match.ok()) << match.message();
  EXPECT_FALSE(match->ok());
  std::printf("90-degree miss: %s (%s)\n", ScanMatchQualityName(match->quality),
              match->reason.c_str());
}

TEST(PlIcpTest, RejectsMalformedInput) {
  const auto room = test_scans::RoomWithBoxes();
  const LaserScan scan = CastScan(room, kReferencePose, ScanSpec{});
  EXPECT_EQ(MatchScans(scan, scan, Pose2d(NAN, 0, 0)).code(), StatusCode::kInvalidInput);
  LaserScan zero_increment = scan;
  zero_increment.angle_increment_rad = 0.0;
  EXPECT_EQ(MatchScans(scan, zero_increment, Pose2d::Zero()).code(), StatusCode::kInvalidInput);
  LaserScan nan_angle = scan;
  nan_angle.angle_min_rad = NAN;
  EXPECT_EQ(MatchScans(nan_angle, scan, Pose2d::Zero()).code(), StatusCode::kInvalidInput);
  PlIcpOptions bad;
  bad.correspondence.max_distance_m = -1.0;
  EXPECT_EQ(MatchScans(scan, scan, Pose2d::Zero(), bad).code(), StatusCode::kInvalidInput);
  // Different beam counts are two different sensors' scans, not an error.
  ScanSpec fine;
  fine.beams = 1081;
  const LaserScan dense = CastScan(room, Compose(kReferencePose, Pose2d(0.1, 0, 0.05)), fine);
  const StatusOr<ScanMatch> match = MatchScans(scan, dense, Pose2d(0.08, 0.01, 0.04));
  ASSERT_TRUE(match.ok()) << match.message();
  EXPECT_TRUE(match->ok()) << match->reason;
  EXPECT_LT(PoseError(match->reference_T_current, Pose2d(0.1, 0, 0.05)), 1e-3);
}

// A sensor moving during its sweep: with the sweep's twist the points are moved to the stamp
// and the match is exact again.
TEST(PlIcpTest, DeskewingRestoresExactRecovery) {
  const auto room = test_scans::RoomWithBoxes();
  ScanSpec spec;
  spec.sweep_time_s = 0.1;
  spec.velocity = Twist2d(0.8, 0.1, 0.9);
  const Pose2d truth = Exp<double>(spec.velocity * 0.1);  // One sweep later.
  const LaserScan reference = CastScan(room, kReferencePose, spec);
  const LaserScan current = CastScan(room, Compose(kReferencePose, truth), spec);
  PlIcpOptions options;
  const StatusOr<ScanMatch> skewed = MatchScans(reference, current, truth, options);
  ASSERT_TRUE(skewed.ok());
  options.reference_points.sweep = SweepMotion::Constant(spec.velocity);
  options.current_points.sweep = SweepMotion::Constant(spec.velocity);
  const StatusOr<ScanMatch> deskewed = MatchScans(reference, current, truth, options);
  ASSERT_TRUE(deskewed.ok());
  EXPECT_TRUE(deskewed->ok()) << deskewed->reason;
  EXPECT_LT(PoseError(deskewed->reference_T_current, truth), 1e-6);
  std::printf("error without de-skewing %.2e, with %.2e\n",
              PoseError(skewed->reference_T_current, truth),
              PoseError(deskewed->reference_T_current, truth));
}

// A robot that turns harder halfway through the sweep: one average velocity leaves the scans
// bent (a few mm), the two pieces make the match exact.
TEST(PlIcpTest, PiecewiseDeskewingFollowsAnAcceleratingSweep) {
  const auto room = test_scans::RoomWithBoxes();
  ScanSpec spec;
  spec.sweep_time_s = 0.1;
  spec.motion = SweepMotion{{0.0, 0.05}, {Twist2d(0.4, 0.0, 0.2), Twist2d(0.9, 0.05, 1.6)}};
  const Pose2d truth = spec.motion->StampTSensor({0.1})[0];  // One sweep later.
  const LaserScan reference = CastScan(room, kReferencePose, spec);
  const LaserScan current = CastScan(room, Compose(kReferencePose, truth), spec);
  PlIcpOptions options;
  options.reference_points.sweep = options.current_points.sweep =
      SweepMotion::Constant(Log(truth) / 0.1);
  const StatusOr<ScanMatch> average = MatchScans(reference, current, truth, options);
  options.reference_points.sweep = options.current_points.sweep = spec.motion;
  const StatusOr<ScanMatch> pieces = MatchScans(reference, current, truth, options);
  ASSERT_TRUE(average.ok() && pieces.ok());
  EXPECT_TRUE(pieces->ok()) << pieces->reason;
  EXPECT_GT(PoseError(average->reference_T_current, truth), 1e-4);
  EXPECT_LT(PoseError(pieces->reference_T_current, truth), 1e-6);
  std::printf("error with the average velocity %.2e, with the pieces %.2e\n",
              PoseError(average->reference_T_current, truth),
              PoseError(pieces->reference_T_current, truth));
}

// The pieces compose: a constant velocity is Exp(ξ·t) at any time (also beyond half a turn and
// before the stamp), a piecewise motion is continuous at its knots, and times may come in any
// order; a motion out of time order or not finite is refused.
TEST(SweepMotionTest, PiecesComposeAndBadMotionsAreRefused) {
  const Twist2d xi(0.7, -0.1, 4.0);
  const std::vector<double> times{0.3, -0.05, 0.0, 1.0, 0.2};
  const std::vector<Pose2d> constant = SweepMotion::Constant(xi).StampTSensor(times);
  for (size_t k = 0; k < times.size(); ++k) {
    EXPECT_LT(PoseError(constant[k], Exp<double>(xi * times[k])), 1e-12) << times[k];
  }
  const SweepMotion two{{0.0, 0.04}, {xi, Twist2d(0.2, 0.0, -1.0)}};
  const std::vector<Pose2d> at = two.StampTSensor({0.04 - 1e-9, 0.04, 0.07, 0.01});
  EXPECT_LT(PoseError(at[0], at[1]), 1e-8);
  EXPECT_LT(PoseError(at[2], Compose(Exp<double>(xi * 0.04), Exp<double>(two.velocity[1] * 0.03))),
            1e-12);
  EXPECT_LT(PoseError(at[3], Exp<double>(xi * 0.01)), 1e-12);
  LaserScan scan = CastScan(test_scans::RoomWithBoxes(), kReferencePose, ScanSpec());
  scan.time_increment_s = 1e-4;
  ScanPointsOptions options;
  options.sweep = SweepMotion{{0.0, 0.04, 0.02}, {xi, xi, xi}};
  EXPECT_FALSE(MakeScanPoints(scan, options).ok());
  options.sweep = SweepMotion{{0.01}, {xi}};
  EXPECT_FALSE(MakeScanPoints(scan, options).ok());
  options.sweep = SweepMotion::Constant(Twist2d(0.1, std::nan(""), 0.0));
  EXPECT_FALSE(MakeScanPoints(scan, options).ok());
  options.sweep = two;
  EXPECT_TRUE(MakeScanPoints(scan, options).ok());
}

// Every beam's own angle finds that beam, on 270° scans (beyond π from angle_min the wrapped
// offset alone had found none: a third of the beams), with either sign of the increment (a
// mirrored scan's), and on a full circle; beyond a partial scan's ends, the end beam.
TEST(ScanPointsTest, NearestBeamOfEveryBeamsAngleIsThatBeam) {
  for (const double span_rad : {1.5 * M_PI, 2.0 * M_PI * 1080.0 / 1081.0, 0.5}) {
    for (const double sign : {1.0, -1.0}) {
      LaserScan scan;
      scan.angle_min_rad = -sign * 0.5 * span_rad;
      scan.angle_increment_rad = sign * span_rad / 1080.0;
      scan.ranges_m.assign(1081, 2.0f);
      scan.range_max_m = 10.0;
      const StatusOr<ScanPoints> points = MakeScanPoints(scan);
      ASSERT_TRUE(points.ok()) << points.message();
      for (int b = 0; b < points->NumBeams(); ++b) {
        ASSERT_EQ(points->NearestBeam(scan.BeamAngle(b) + 0.3 * scan.angle_increment_rad), b)
            << "span " << span_rad << " sign " << sign;
      }
      if (span_rad < M_PI) {
        EXPECT_EQ(points->NearestBeam(scan.BeamAngle(0) - sign * 0.2), 0);
        EXPECT_EQ(points->NearestBeam(scan.BeamAngle(1080) + sign * 0.2), 1080);
      }
    }
  }
  EXPECT_EQ(ScanPoints().NearestBeam(0.0), -1);
}

// A sweep de-skewed through a fast turn (±5 rad/s over 0.1 s: the last beams turned 0.5 rad, tens
// of beams from their nominal angles): the beam found for each beam's de-skewed angle looks along
// it, returns and missing returns alike (by the nominal angles, the scan points' correspondences
// had been searched among the wrong beams).
TEST(ScanPointsTest, NearestBeamFollowsADeskewedSweep) {
  for (const int beams : {1081, 360}) {
    for (const double omega : {5.0, -5.0}) {
      LaserScan scan;
      const double span_rad = beams == 360 ? 2.0 * M_PI * 359.0 / 360.0 : 1.5 * M_PI;
      scan.angle_min_rad = -0.5 * span_rad;
      scan.angle_increment_rad = span_rad / (beams - 1);
      scan.time_increment_s = 0.1 / beams;
      scan.ranges_m.assign(beams, 2.0f);
      for (int b = 0; b < beams; b += 7) scan.ranges_m[b] = std::numeric_limits<float>::infinity();
      scan.range_max_m = 10.0;
      ScanPointsOptions options;
      options.sweep = SweepMotion::Constant(Twist2d(0.0, 0.0, omega));
      const StatusOr<ScanPoints> points = MakeScanPoints(scan, options);
      ASSERT_TRUE(points.ok()) << points.message();
      for (int b = 0; b < beams; ++b) {
        const double phi = points->beam_angle_rad[b];
        ASSERT_NEAR(phi, scan.BeamAngle(b) + omega * b * scan.time_increment_s, 1e-9);
        const int found = points->NearestBeam(phi);
        // Half the de-skewed beams' spacing (on a full circle the turn's overlap has two beams
        // along an angle: either will do).
        ASSERT_LE(std::abs(WrapAngle(points->beam_angle_rad[found] - phi)),
                  0.5 * (scan.angle_increment_rad + std::abs(omega) * scan.time_increment_s))
            << beams << " beams, ω " << omega << ", beam " << b << " found " << found;
      }
    }
  }
}

// The trig-free search finds the same nearest point as brute force, the repeated search the same
// as FindCorrespondences (every stride-th point with a stride), and each line straddles its
// nearest point: one end on either side, at least min_segment_length_m / 2 from it.
TEST(CorrespondencesTest, SearchMatchesBruteForceAndLinesStraddleTheNearestPoint) {
  const auto room = test_scans::RoomWithBoxes();
  ScanSpec spec;
  spec.beams = 1081;
  spec.fov_rad = 1.5 * M_PI;
  spec.range_sigma_m = 0.01;
  std::mt19937 rng(5);
  const StatusOr<ScanPoints> reference = MakeScanPoints(CastScan(room, kReferencePose, spec, &rng));
  const Pose2d motion(0.12, -0.05, 0.08);
  const StatusOr<ScanPoints> current =
      MakeScanPoints(CastScan(room, Compose(kReferencePose, motion), spec, &rng));
  ASSERT_TRUE(reference.ok() && current.ok());
  std::vector<Eigen::Vector2d> moved;
  for (const Eigen::Vector2d& p : current->points_m) {
    moved.push_back(Compose(motion, Pose2d(p.x(), p.y(), 0.0)).head<2>());
  }
  const CorrespondenceOptions options;
  std::vector<Correspondence> found;
  FindCorrespondences(*reference, moved, options, &found);
  ASSERT_GT(found.size(), moved.size() * 9 / 10);
  int straddling = 0;
  for (const Correspondence& c : found) {
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector2d& q : reference->points_m) {
      best = std::min(best, (q - moved[c.current]).norm());
    }
    EXPECT_NEAR((reference->points_m[c.reference_a] - moved[c.current]).norm(), best, 1e-12);
    if (c.line_a == c.reference_a) {
      EXPECT_EQ(c.line_b, c.reference_b);
      continue;
    }
    ++straddling;
    const int beam = reference->beams[c.reference_a];
    EXPECT_LT(reference->beams[c.line_a], beam);
    EXPECT_GT(reference->beams[c.line_b], beam);
    for (int end : {c.line_a, c.line_b}) {
      const double d = (reference->points_m[end] - reference->points_m[c.reference_a]).norm();
      EXPECT_GE(d, 0.5 * options.min_segment_length_m);
      EXPECT_LE(d, options.max_segment_length_m);
    }
  }
  EXPECT_GT(straddling, static_cast<int>(found.size()) * 8 / 10);
  const CorrespondenceSearch search(*reference, options);
  std::vector<Correspondence> strided;
  search.Find(moved, 3, &strided);
  std::vector<Correspondence> expected;
  for (const Correspondence& c : found) {
    if (c.current % 3 == 0) expected.push_back(c);
  }
  ASSERT_EQ(strided.size(), expected.size());
  for (size_t k = 0; k < strided.size(); ++k) {
    EXPECT_EQ(strided[k].current, expected[k].current);
    EXPECT_EQ(strided[k].line_a, expected[k].line_a);
    EXPECT_EQ(strided[k].line_b, expected[k].line_b);
  }
}

// Consecutive simulated scans (1 cm of range noise, 2 % missing) matched from a zero guess: the
// implied range noise is unbiased and the errors' d² = eᵀΣ⁻¹e follow χ²₃ (mean 3, 95.4 % below
// 8.02, 89.7 % below 6.18), where a line through the nearest point itself gave σ̂ ≈ 6 mm and 45 %
// below 6.18 at 1081 beams. Without the coarse phase the poses are the same within 0.5σ.
void ExpectHonestCovarianceOnSimulatedScans(int beams, double fov_rad) {
  ScanSimOptions o;
  o.laser = DefaultScanLaserOptions();
  o.laser.num_intervals = 40;
  o.laser.seed = 11;
  o.beams = beams;
  o.field_of_view_rad = fov_rad;
  o.range_noise_sigma_m = 0.01;
  o.missing_probability = 0.02;
  o.seed = 11;
  const StatusOr<ScanSimulation> sim = SimulateScans(o);
  ASSERT_TRUE(sim.ok()) << sim.message();
  PlIcpOptions all_points;
  all_points.coarse_points = 0;
  int pairs = 0, within = 0, within_3dof = 0;
  double sum_d2 = 0.0, sum_sigma = 0.0;
  for (size_t i = 1; i < sim->scans.size(); ++i) {
    const StatusOr<ScanMatch> m = MatchScans(sim->scans[i - 1], sim->scans[i], Pose2d::Zero());
    ASSERT_TRUE(m.ok()) << m.message();
    ASSERT_TRUE(m->ok()) << m->reason;
    const Pose2d truth = Between(sim->truth.world_T_sensor[i - 1], sim->truth.world_T_sensor[i]);
    Eigen::Vector3d e = m->reference_T_current - truth;
    e(2) = WrapAngle(e(2));
    const double d2 = e.dot(m->covariance.ldlt().solve(e));
    sum_d2 += d2;
    within += d2 < 6.18;
    within_3dof += d2 < 8.02;
    sum_sigma += m->range_sigma_m;
    ++pairs;
    const StatusOr<ScanMatch> fine =
        MatchScans(sim->scans[i - 1], sim->scans[i], Pose2d::Zero(), all_points);
    ASSERT_TRUE(fine.ok() && fine->ok());
    Eigen::Vector3d d = fine->reference_T_current - m->reference_T_current;
    d(2) = WrapAngle(d(2));
    EXPECT_LT(d.dot(m->covariance.ldlt().solve(d)), 0.5 * 0.5);
  }
  std::printf("%d beams: of %d pairs %d have d2 < 6.18, %d d2 < 8.02; mean d2 %.2f; sigma %.4f m\n",
              beams, pairs, within, within_3dof, sum_d2 / pairs, sum_sigma / pairs);
  EXPECT_NEAR(sum_sigma / pairs, 0.0105, 0.0015);
  EXPECT_GE(within, pairs * 75 / 100);
  EXPECT_GE(within_3dof, pairs * 85 / 100);
  EXPECT_GT(sum_d2 / pairs, 2.0);
  EXPECT_LT(sum_d2 / pairs, 4.5);
}

TEST(PlIcpTest, CovarianceIsHonestOnSimulatedScans360) {
  ExpectHonestCovarianceOnSimulatedScans(360, 2.0 * M_PI);
}

TEST(PlIcpTest, CovarianceIsHonestOnSimulatedScans1081) {
  ExpectHonestCovarianceOnSimulatedScans(1081, 1.5 * M_PI);
}

// Prints the throughput; asserts nothing about time (the machine is shared).
TEST(PlIcpTest, ReportsScansPerSecond) {
  const auto room = test_scans::RoomWithBoxes();
  for (int beams : {360, 1081}) {
    ScanSpec spec;
    spec.beams = beams;
    spec.fov_rad = beams == 360 ? 2.0 * M_PI : 1.5 * M_PI;
    spec.range_sigma_m = 0.01;
    std::mt19937 rng(3);
    std::vector<LaserScan> scans;
    const Pose2d step(0.05, 0.01, 0.03);
    Pose2d pose = kReferencePose;
    for (int i = 0; i < 21; ++i) {
      scans.push_back(CastScan(room, pose, spec, &rng));
      pose = Compose(pose, step);
    }
    const int repeats = beams == 360 ? 20 : 8;
    int matched = 0;
    const auto start = std::chrono::steady_clock::now();
    for (int r = 0; r < repeats; ++r) {
      for (size_t i = 1; i < scans.size(); ++i) {
        const StatusOr<ScanMatch> match =
            MatchScans(scans[i - 1], scans[i], step + Pose2d(0.01, -0.01, 0.005));
        matched += match.ok() && match->ok();
      }
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int total = repeats * static_cast<int>(scans.size() - 1);
    std::printf("%d beams: %.0f scans/s (%d of %d matches ok)\n", beams, total / seconds, matched,
                total);
    EXPECT_EQ(matched, total);
  }
}

}  // namespace
}  // namespace calib
