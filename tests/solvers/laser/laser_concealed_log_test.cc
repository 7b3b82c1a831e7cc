// The laser logs of data/diagnose that are meant to conceal their effect do.
#include <gtest/gtest.h>

#include "tests/solvers/laser/laser_diagnosis_recipes.h"

namespace calib {
namespace {

using ::calib::testing::ConcealedRecipes;
using ::calib::testing::Concealment;
using ::calib::testing::MeasureConcealment;
using ::calib::testing::Recipe;

// The "concealed": the base fit's residual σ within 5 % of that of the same log without
// the effect, while some base parameter is ≥ 3 σ from the truth.
class ConcealedLogTest : public ::testing::TestWithParam<Recipe> {};

TEST_P(ConcealedLogTest, HidesItsEffect) {
  const Recipe& recipe = GetParam();
  const Concealment c = MeasureConcealment(recipe);
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(c.sigma_ratio(j), 1.0, 0.05) << recipe.name << " component " << j;
  }
  EXPECT_GE(c.error_sigmas.cwiseAbs().maxCoeff(), 3.0)
      << recipe.name << ": " << c.error_sigmas.transpose();
}

INSTANTIATE_TEST_SUITE_P(DataDiagnose, ConcealedLogTest, ::testing::ValuesIn(ConcealedRecipes()),
                         [](const ::testing::TestParamInfo<Recipe>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace calib
