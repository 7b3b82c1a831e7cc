#include <calib/core/bearing/bearing_params.h>
#include <gtest/gtest.h>

#include <string>

namespace calib {
namespace {

TEST(BearingParamsTest, TablesMatchTheNamesAndLayout) {
  for (int i = 0; i < kNumBearingParams; ++i) {
    EXPECT_EQ(std::string(kBearingParams[i].name), kBearingParamNames[i]);
    EXPECT_EQ(kBearingParams[i].is_angle, i == kBearingPhi || i == kBearingPsi) << i;
  }
  for (int i = 0; i < kNumBearingMetricParams; ++i) {
    EXPECT_EQ(std::string(kBearingMetricParams[i].name), kBearingMetricNames[i]);
    EXPECT_EQ(kBearingMetricParams[i].is_angle, i == kBearingMetricPhi || i == kBearingMetricPsi);
  }
  EXPECT_STREQ(kBearingParams[kBearingDelta].unit, "");
  EXPECT_STREQ(kBearingParams[kBearingXi].unit, "1/m");
}

TEST(BearingParamsTest, VectorRoundTripAndMetricConversion) {
  const BearingMetricParams m{0.3, 0.5, -0.2, 1.02, 0.97, 1.01};
  const double wheelbase_m = 0.4;
  const BearingParams p = ObservableParams(m, wheelbase_m);
  const BearingParamVector v = ToVector(p);
  EXPECT_EQ(ToVector(BearingParamsFromVector(v)), v);
  EXPECT_DOUBLE_EQ(v(kBearingEta), m.delta_r / (2.0 * m.rho_m));
  const BearingMetricVector back = ToVector(MetricParams(p, m.rho_m, wheelbase_m));
  EXPECT_NEAR((back - ToVector(m)).cwiseAbs().maxCoeff(), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(back(kBearingMetricRho), m.rho_m);
}

}  // namespace
}  // namespace calib
