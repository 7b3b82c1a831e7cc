// The statement writer (solvers/diagnosis/statement.h): the sentence's structure for every
// problem, and shifts in σ that never divide by zero.
#include <calib/solvers/diagnosis/statement.h>
#include <gtest/gtest.h>

#include <cmath>

namespace calib {
namespace {

std::vector<ParamWords> TwoParams() { return {{"a", 1000.0, " mm"}, {"b", 180.0 / M_PI, "°"}}; }

TEST(StatementTest, ShiftInSigmasIsZeroWhereSigmaIsZero) {
  const Eigen::VectorXd shift = Eigen::Vector3d(1.0, -2.0, 3.0);
  const Eigen::VectorXd sigma = Eigen::Vector3d(0.5, 0.0, std::nan(""));
  const Eigen::VectorXd z = ShiftInSigmas(shift, sigma);
  EXPECT_DOUBLE_EQ(z(0), 2.0);
  EXPECT_EQ(z(1), 0.0);  // Not −inf.
  EXPECT_EQ(z(2), 0.0);  // Not NaN.
  EXPECT_TRUE(z.allFinite());
}

TEST(StatementTest, ShiftWordsNameTheLargestShifts) {
  const Eigen::VectorXd shift = Eigen::Vector2d(0.002, 0.01);
  EXPECT_EQ(ShiftWords(shift, Eigen::Vector2d(4.0, 0.5), TwoParams()), "a +2 mm (4.0 σ)");
  EXPECT_EQ(ShiftWords(shift, Eigen::Vector2d(4.0, -2.0), TwoParams()),
            "a +2 mm (4.0 σ) and b +0.573° (2.0 σ)");
}

TEST(StatementTest, SentencesForEachOutcome) {
  Finding f;
  f.name = "drift";
  f.unit = "s";
  StatementWords words;
  words.base = "parameters";
  words.params = TwoParams();
  words.confounded = "Drift is absorbed.";
  words.adopted = "The thing drifts by 3 ± 1 s";
  words.estimate = "; one-step estimate 3 ± 1 s";
  f.no_information = true;
  EXPECT_EQ(WriteStatement(f, words),
            "The log's motion does not excite drift at all (no sensitivity): it can be neither "
            "found nor excluded.");
  f.no_information = false;
  f.confounded = true;
  EXPECT_EQ(WriteStatement(f, words), "Drift is absorbed.");
  f.confounded = false;
  f.statistic = 2.0;
  f.p_value = 0.2;
  f.concealment = 0.25;
  EXPECT_EQ(WriteStatement(f, words),
            "No drift adopted: score test 2.0, p = 0.200, 25 % of it absorbable by the base "
            "parameters; one-step estimate 3 ± 1 s.");
  f.refitted = true;
  f.holm_level = 0.01;
  f.lr_p_value = 0.5;
  EXPECT_NE(WriteStatement(f, words).find("the likelihood-ratio test did not confirm it"),
            std::string::npos);
  f.significant = true;
  f.heldout_reduction = 0.1;
  f.base_shift = Eigen::Vector2d(0.002, 0.0);
  f.base_shift_sigmas = Eigen::Vector2d(4.0, 0.0);
  words.covariate = "the speed";
  f.location.covariate = "speed";
  const std::string adopted = WriteStatement(f, words);
  EXPECT_EQ(adopted.rfind("The thing drifts by 3 ± 1 s (score test 2.0, p = 0.200, 25 % of it "
                          "absorbable by the base parameters); the base fit had absorbed it as "
                          "a +2 mm (4.0 σ); modelling it cuts the held-out residual cost by "
                          "10.0 %; it follows the speed",
                          0),
            0u)
      << adopted;
  f.absorbed_share = 0.9;  // Measured: "hidden" instead of "absorbable".
  EXPECT_NE(WriteStatement(f, words).find("90 % of it hidden by the base parameters"),
            std::string::npos);
}

}  // namespace
}  // namespace calib
