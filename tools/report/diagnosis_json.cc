#include <calib/tools/report/diagnosis_json.h>

#include <cmath>
#include <filesystem>

namespace calib {
namespace {

using Json = nlohmann::ordered_json;

// Non-finite numbers are written as null.
Json Number(double x) {
  if (!std::isfinite(x)) return nullptr;
  return x;
}

Json Vector(const Eigen::VectorXd& v) {
  Json array = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) array.push_back(Number(v(i)));
  return array;
}

// {name: value} over the parameter table.
Json ParamObject(const Eigen::VectorXd& v, const ParamTable& params) {
  Json object = Json::object();
  for (size_t i = 0; i < params.size() && static_cast<Eigen::Index>(i) < v.size(); ++i) {
    object[params[i].name] = Number(v(i));
  }
  return object;
}

Json LocationJson(const MismatchLocation& location) {
  Json windows = Json::array();
  for (const MismatchLocation::Window& w : location.windows) {
    windows.push_back(
        {{"start_s", w.start_s}, {"end_s", w.end_s}, {"share", w.share}, {"rate", w.rate}});
  }
  return {
      {"covariate", location.covariate}, {"explained", location.explained}, {"windows", windows}};
}

// The score test, one-step estimate and what the base fit absorbed (testable findings).
void AddScoreTest(const Finding& f, const ParamTable& params, Json* out) {
  (*out)["score_test"] = {
      {"step", f.step},       {"statistic", f.statistic},   {"dof", f.dof},
      {"p_value", f.p_value}, {"holm_level", f.holm_level}, {"significant", f.score_significant}};
  (*out)["one_step"] = {{"value", Vector(f.one_step)}, {"stddev", Vector(f.one_step_stddev)}};
  (*out)["absorbed_by_base"] = ParamObject(f.absorbed, params);
}

void AddConfirmation(const Finding& f, Json* out) {
  (*out)["likelihood_ratio"] = {{"statistic", f.lr_statistic},
                                {"p_value", f.lr_p_value},
                                {"delta_aic", f.delta_aic},
                                {"delta_bic", f.delta_bic}};
  (*out)["held_out"] = {{"cost_before", f.heldout_cost_before},
                        {"cost_after", f.heldout_cost_after},
                        {"reduction", f.heldout_reduction},
                        {"rms_before", f.heldout_rms_before},
                        {"rms_after", f.heldout_rms_after}};
}

}  // namespace

std::string FindingPlotName(const Finding& finding) {
  // A finding located along no covariate (the stamp jitter) is named alone.
  const std::string& covariate = finding.location.covariate;
  return finding.name + (covariate.empty() ? "" : "_vs_" + covariate) + ".svg";
}

Json FitReportJson(const FitReport& fit) {
  Json out;
  out["effects"] = fit.effects;
  out["estimate"] = ParamObject(fit.estimate, fit.params);
  out["stddev"] = ParamObject(fit.stddev, fit.params);
  out["rms"] = Vector(fit.rms);
  out["rms_units"] = fit.rms_units;
  out["robust_cost"] = fit.robust_cost;
  out["inliers"] = fit.inliers;
  Json values = Json::object();
  for (const EffectValue& e : fit.effect_values) {
    Json value = {{"value", Number(e.value)}, {"stddev", Number(e.stddev)}, {"unit", e.unit}};
    if (e.gamma.size() > 0) {
      value["gamma"] = Vector(e.gamma);
      value["gamma_stddev"] = Vector(e.gamma_stddev);
    }
    values[e.name] = value;
  }
  out["effect_values"] = values;
  for (const auto& [key, text] : fit.words) out[key] = text;
  return out;
}

Json FindingJson(const ReportedFinding& reported, const ParamTable& params,
                 const std::vector<std::string>& plots) {
  const Finding& f = reported.finding;
  Json out;
  out["effect"] = f.name;
  // Statistically significant; `implausible` says it was not adopted as that physics.
  out["significant"] = f.significant || f.implausible;
  out["value"] = f.testable() ? Number(f.value) : Json(nullptr);
  out["stddev"] = f.testable() ? Number(f.stddev) : Json(nullptr);
  out["unit"] = f.unit;
  out["statement"] = f.statement;
  if (f.confounded) out["confounded_with"] = f.confounded_with;
  if (f.implausible) {
    out["implausible"] = true;
    out["reason"] = f.implausible_reason;
    out["follows"] = f.follows;
  }
  out["no_information"] = f.no_information;
  if (f.testable()) {
    for (const auto& [key, value] : reported.extra) out[key] = Number(value);
  }
  out["concealment"] = Number(f.concealment);
  if (f.testable()) AddScoreTest(f, params, &out);
  if (f.refitted) AddConfirmation(f, &out);
  if (!f.location.covariate.empty()) out["location"] = LocationJson(f.location);
  if (f.significant) {
    out["base_shift"] = ParamObject(f.base_shift, params);
    out["base_shift_sigmas"] = ParamObject(f.base_shift_sigmas, params);
    out["absorbed_share"] = Number(f.absorbed_share);
    out["profile"] = ProfileJson(f.profile);
    for (const std::string& plot : plots) {
      if (std::filesystem::path(plot).filename() == FindingPlotName(f)) out["plot"] = plot;
    }
  }
  return out;
}

Json ProfileJson(const CovariateProfile& profile) {
  Json out;
  out["covariate"] = profile.name;
  out["unit"] = profile.unit;
  out["center"] = profile.center;
  const auto rows = [](const std::vector<Eigen::VectorXd>& values) {
    Json array = Json::array();
    for (const Eigen::VectorXd& v : values) array.push_back(Vector(v));
    return array;
  };
  const Eigen::Index channels = profile.before_mean.empty() ? 0 : profile.before_mean[0].size();
  if (!profile.channel_labels.empty()) {
    out["channels"] = channels == 1 ? Json({"bearing [rad]"})
                                    : Json({"bearing [rad]", "along the effect [sigma]"});
  } else {
    out["channels"] = channels == 0 || channels == 3
                          ? Json({"x [m]", "y [m]", "theta [rad]"})
                          : Json({"x [m]", "y [m]", "theta [rad]", "along the effect [sigma]"});
  }
  out["before_mean"] = rows(profile.before_mean);
  out["before_stderr"] = rows(profile.before_stderr);
  out["after_mean"] = rows(profile.after_mean);
  out["after_stderr"] = rows(profile.after_stderr);
  out["before_p_value"] = profile.before_p_value;
  out["after_p_value"] = profile.after_p_value;
  return out;
}

Json StructureJson(const ResidualStructure& structure) {
  Json out;
  out["found"] = structure.found;
  out["covariate"] = structure.covariate.empty() ? Json(nullptr) : Json(structure.covariate);
  out["p_value"] = structure.p_value;
  out["change_time_s"] =
      structure.change_time_s >= 0.0 ? Number(structure.change_time_s) : Json(nullptr);
  out["change_p_value"] = structure.change_p_value;
  out["statement"] = structure.statement;
  return out;
}

Json DiagnosisJson(const DiagnosisReport& report, const std::string& input,
                   const std::vector<std::string>& plots) {
  Json out;
  out["problem"] = report.problem;
  out["input"] = input;
  out["samples"] = report.samples;
  out["units"] = report.units;
  out["baseline"] = FitReportJson(report.baseline);
  Json findings = Json::array();
  for (const ReportedFinding& f : report.findings) {
    findings.push_back(FindingJson(f, report.params, plots));
  }
  out["findings"] = findings;
  out["final"] = FitReportJson(report.final_fit);
  out["adopted"] = report.adopted;
  out["residual_structure"] = {{"before", StructureJson(report.structure_before)},
                               {"after", StructureJson(report.structure_after)}};
  Json profiles = Json::array();
  for (const CovariateProfile& profile : report.covariates)
    profiles.push_back(ProfileJson(profile));
  out["figures"] = {{"rms_before", Vector(report.baseline.rms)},
                    {"rms_after", Vector(report.final_fit.rms)},
                    {"robust_cost_before", report.baseline.robust_cost},
                    {"robust_cost_after", report.final_fit.robust_cost},
                    {"covariates", profiles},
                    {"plots", plots}};
  out["notes"] = report.notes;
  out["steps"] = report.steps;
  out["seconds"] = report.seconds;
  return out;
}

}  // namespace calib
