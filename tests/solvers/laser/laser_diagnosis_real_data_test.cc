// The laser diagnosis on the published recordings with a known effect injected (skips when the
// recordings are absent).
#include <calib/core/laser/laser_log_io.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_diagnosis.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <vector>

#include "tests/problems/laser/laser_effect_gamma.h"

namespace calib {
namespace {

namespace fs = std::filesystem;

using ::calib::testing::EffectVector;
using ::calib::testing::Gamma;

const fs::path kCensiDir = CALIB_CENSI_DATA_DIR;

class CensiInjectionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kCensiDir / "l90.tuple")) {
      GTEST_SKIP() << "the published recordings are not at " << kCensiDir
                   << " (they are not part of the repository)";
    }
    const StatusOr<LaserLog> log = ReadLaserLog((kCensiDir / "l90.tuple").string());
    ASSERT_TRUE(log.ok()) << log.message();
    intervals_ = log->intervals;
  }

  // The one-effect diagnosis; returns the finding.
  LaserFinding Diagnose(const std::vector<LaserInterval>& intervals, LaserEffect effect) {
    LaserDiagnosisOptions options;
    options.candidates = {effect};
    const StatusOr<LaserDiagnosis> d = DiagnoseLaser(intervals, options);
    EXPECT_TRUE(d.ok()) << d.message();
    for (const LaserFinding& f : d->findings) {
      if (f.effect == effect) return f;
    }
    ADD_FAILURE() << "no finding for " << LaserEffectName(effect);
    return LaserFinding();
  }

  std::vector<LaserInterval> intervals_;
};

// Re-mixing neighbouring wheel speeds, φ'_k = (1 − a)·φ_k + a·φ_{k+1}, makes interval k's wheels
// those of [t_k + a·T, t_{k+1} + a·T]: the scans now run a·T early, a time offset of −a·T.
TEST_F(CensiInjectionTest, InjectedTimeShiftIsFound) {
  const double a = 0.1;
  std::vector<LaserInterval> shifted = intervals_;
  double sum_t = 0.0;
  for (size_t k = 0; k + 1 < shifted.size(); ++k) {
    shifted[k].left_speed = (1 - a) * intervals_[k].left_speed + a * intervals_[k + 1].left_speed;
    shifted[k].right_speed =
        (1 - a) * intervals_[k].right_speed + a * intervals_[k + 1].right_speed;
    sum_t += intervals_[k].duration_s;
  }
  const double injected = -a * sum_t / (shifted.size() - 1);
  const LaserFinding before = Diagnose(intervals_, LaserEffect::kTimeOffset);
  const LaserFinding after = Diagnose(shifted, LaserEffect::kTimeOffset);
  EXPECT_TRUE(after.significant);
  EXPECT_GT(after.statistic, before.statistic);
  const double change = after.value - before.value;
  EXPECT_LT(std::abs(change - injected), 3.0 * std::hypot(before.stddev, after.stddev))
      << "injected " << injected << " s, found " << before.value << " → " << after.value;
}

// A lateral slip added to sm through the model at the base calibration.
TEST_F(CensiInjectionTest, InjectedLateralSlipIsFound) {
  const double injected = 0.3;  // s: lateral velocity 0.3·v·ω.
  const StatusOr<LaserCalibrationResult> base = CalibrateLaser(intervals_);
  ASSERT_TRUE(base.ok());
  const LaserParamVector v = base->estimate.ToVector();
  const std::vector<LaserEffectContext> contexts =
      BuildLaserEffectContexts(intervals_, BoundarySpeedModel::kSmooth);
  const EffectVector gamma = Gamma(LaserEffect::kLateralSlip, injected);
  const EffectVector zero = EffectVector::Zero();
  const Pose2d mounting(v(3), v(4), v(5));
  std::vector<LaserInterval> slipped = intervals_;
  for (size_t k = 0; k < slipped.size(); ++k) {
    slipped[k].sensor_motion +=
        SensorMotionFromRobotMotion(mounting,
                                    EffectRobotMotion(v.data(), gamma.data(), contexts[k])) -
        SensorMotionFromRobotMotion(mounting,
                                    EffectRobotMotion(v.data(), zero.data(), contexts[k]));
  }
  const LaserFinding before = Diagnose(intervals_, LaserEffect::kLateralSlip);
  const LaserFinding after = Diagnose(slipped, LaserEffect::kLateralSlip);
  EXPECT_TRUE(after.significant);
  const double change = after.value - before.value;
  EXPECT_LT(std::abs(change - injected), 3.0 * std::hypot(before.stddev, after.stddev))
      << "injected " << injected << " s, found " << before.value << " → " << after.value;
}

}  // namespace
}  // namespace calib
