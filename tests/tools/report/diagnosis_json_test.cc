// The one JSON writer of `calib diagnose` (tools/report/diagnosis_json.h): the contract's keys
// and the same schema for the findings of both problems.
#include <calib/tools/report/diagnosis_json.h>
#include <gtest/gtest.h>

#include <set>
#include <string>

namespace calib {
namespace {

std::set<std::string> Keys(const nlohmann::ordered_json& object) {
  std::set<std::string> keys;
  for (const auto& [key, value] : object.items()) keys.insert(key);
  return keys;
}

// A report of a problem with `params` parameters and one adopted, one untested finding.
DiagnosisReport Report(const std::string& problem, const std::vector<ParamInfo>& params) {
  const Eigen::Index n = static_cast<Eigen::Index>(params.size());
  DiagnosisReport report;
  report.problem = problem;
  report.params = params;
  for (FitReport* fit : {&report.baseline, &report.final_fit}) {
    fit->params = params;
    fit->estimate = fit->stddev = Eigen::VectorXd::Ones(n);
    fit->rms = Eigen::VectorXd::Ones(1);
    fit->rms_units = {"rad"};
  }
  report.final_fit.effects = {"drift"};
  report.final_fit.effect_values.push_back({"drift", 0.1, 0.01, "s", {}, {}});
  ReportedFinding adopted;
  Finding& f = adopted.finding;
  f.name = "drift";
  f.unit = "s";
  f.significant = f.score_significant = f.refitted = true;
  f.dof = 1;
  f.one_step = f.one_step_stddev = Eigen::VectorXd::Ones(1);
  f.absorbed = f.base_shift = Eigen::VectorXd::Ones(n);
  f.base_shift_sigmas = Eigen::VectorXd::Zero(n);
  f.location.covariate = "time";
  report.findings.push_back(adopted);
  ReportedFinding confounded;
  confounded.finding.name = "slip";
  confounded.finding.confounded = true;
  confounded.finding.confounded_with = {params[0].name};
  report.findings.push_back(confounded);
  report.adopted = {"drift"};
  return report;
}

TEST(DiagnosisJsonTest, OneSchemaForBothProblems) {
  const std::vector<ParamInfo> laser = {{"r_l", "m", false, 1e3, "mm"},
                                        {"sensor_theta", "rad", true, 57.3, "deg"}};
  const std::vector<ParamInfo> bearing = {{"phi", "rad", true, 57.3, "deg"},
                                          {"eta", "1/m", false, 1.0, "1/m"},
                                          {"xi", "1/m", false, 1.0, "1/m"}};
  const nlohmann::ordered_json a = DiagnosisJson(Report("laser", laser), "in", {});
  const nlohmann::ordered_json b = DiagnosisJson(Report("bearing", bearing), "in", {});
  EXPECT_EQ(Keys(a), Keys(b));
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(Keys(a["findings"][i]), Keys(b["findings"][i])) << i;
  }
  EXPECT_EQ(Keys(a["baseline"]), Keys(b["baseline"]));
  EXPECT_EQ(Keys(a["findings"][0]["base_shift"]), std::set<std::string>({"r_l", "sensor_theta"}));
  EXPECT_EQ(Keys(b["findings"][0]["absorbed_by_base"]),
            std::set<std::string>({"phi", "eta", "xi"}));
}

TEST(DiagnosisJsonTest, ContractKeys) {
  const nlohmann::ordered_json j =
      DiagnosisJson(Report("laser", {{"r_l", "m", false, 1e3, "mm"}}), "in", {});
  for (const char* key : {"baseline", "findings", "final"}) EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_TRUE(j["baseline"].contains("estimate"));
  EXPECT_TRUE(j["baseline"]["rms"].is_array());
  EXPECT_EQ(j["final"]["effects"], nlohmann::ordered_json({"drift"}));
  EXPECT_TRUE(j["final"].contains("estimate"));
  for (const auto& f : j["findings"]) {
    for (const char* key : {"effect", "significant", "value", "stddev", "unit", "statement"}) {
      EXPECT_TRUE(f.contains(key)) << key;
    }
  }
  const auto& confounded = j["findings"][1];
  EXPECT_FALSE(confounded["significant"].get<bool>());
  EXPECT_EQ(confounded["confounded_with"], nlohmann::ordered_json({"r_l"}));
  EXPECT_TRUE(confounded["value"].is_null());
  // A zero σ gives a zero shift in σ, and an unmeasured share is null, never inf or NaN.
  EXPECT_EQ(j["findings"][0]["base_shift_sigmas"]["r_l"].get<double>(), 0.0);
  EXPECT_TRUE(j["findings"][0]["absorbed_share"].is_null());
}

}  // namespace
}  // namespace calib
