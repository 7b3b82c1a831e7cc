#include <calib/tools/report/bearing_diagnose_report.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <calib/core/bearing/bearing_log_io.h>
#include <calib/solvers/common/robust_loss.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/laser_diagnose_report.h>

namespace calib {
namespace {

namespace fs = std::filesystem;

nlohmann::ordered_json Number(double x) {
  if (!std::isfinite(x)) return nullptr;
  return x;
}

nlohmann::ordered_json ParamVectorJson(const BearingParamVector& v) {
  nlohmann::ordered_json object;
  for (int i = 0; i < kNumBearingParams; ++i) object[kBearingParamNames[i]] = Number(v(i));
  return object;
}

nlohmann::ordered_json FitJson(const BearingFitReport& fit) {
  nlohmann::ordered_json out;
  out["effects"] = fit.with_time_offset ? nlohmann::ordered_json({"time_offset"})
                                        : nlohmann::ordered_json::array();
  const BearingMetricVector metric = ToVector(fit.metric);
  out["estimate"] = BearingParamObject(ToVector(fit.estimate), fit.has_metric ? &metric : nullptr);
  out["stddev"] = BearingParamObject(fit.stddev, fit.has_metric ? &fit.metric_stddev : nullptr);
  out["rms"] = {fit.rms_rad};
  out["rms_units"] = {"rad"};
  out["robust_cost"] = fit.robust_cost;
  out["inliers"] = fit.inliers;
  nlohmann::ordered_json values = nlohmann::ordered_json::object();
  if (fit.with_time_offset) {
    values["time_offset"] = {
        {"value", fit.time_offset_s}, {"stddev", Number(fit.time_offset_stddev_s)}, {"unit", "s"}};
  }
  out["effect_values"] = values;
  return out;
}

std::string PlotName(const BearingFinding& f) {
  return f.name + "_vs_" + f.location.covariate + ".svg";
}

nlohmann::ordered_json FindingJson(const BearingFinding& f, const std::vector<std::string>& plots) {
  nlohmann::ordered_json out;
  out["effect"] = f.name;
  out["significant"] = f.significant;
  const bool estimable = !f.confounded && !f.no_information;
  out["value"] = estimable ? Number(f.value) : nlohmann::ordered_json(nullptr);
  out["stddev"] = estimable ? Number(f.stddev) : nlohmann::ordered_json(nullptr);
  out["unit"] = f.unit;
  out["statement"] = f.statement;
  if (f.confounded) out["confounded_with"] = f.confounded_with;
  out["no_information"] = f.no_information;
  out["score_test"] = {{"statistic", f.statistic},
                       {"dof", f.dof},
                       {"p_value", f.p_value},
                       {"holm_level", f.holm_level},
                       {"significant", f.score_significant}};
  out["concealment"] = Number(f.concealment);
  out["one_step"] = {{"value", Number(f.one_step)}, {"stddev", Number(f.one_step_stddev)}};
  out["absorbed"] = ParamVectorJson(f.absorbed);
  if (f.refitted) {
    out["likelihood_ratio"] = {{"statistic", f.lr_statistic},
                               {"p_value", f.lr_p_value},
                               {"delta_aic", f.delta_aic},
                               {"delta_bic", f.delta_bic}};
    out["held_out"] = {{"cost_before", f.heldout_cost_before},
                       {"cost_after", f.heldout_cost_after},
                       {"rms_before", f.heldout_rms_before},
                       {"rms_after", f.heldout_rms_after},
                       {"reduction", f.heldout_reduction}};
  }
  if (f.significant) {
    out["base_shift"] = ParamVectorJson(f.base_shift);
    out["base_shift_sigmas"] = ParamVectorJson(f.base_shift_sigmas);
  }
  nlohmann::ordered_json windows = nlohmann::ordered_json::array();
  for (const MismatchLocation::Window& w : f.location.windows) {
    windows.push_back(
        {{"start_s", w.start_s}, {"end_s", w.end_s}, {"share", w.share}, {"rate", w.rate}});
  }
  out["location"] = {
      {"covariate", f.location.covariate.empty() ? nlohmann::ordered_json(nullptr)
                                                 : nlohmann::ordered_json(f.location.covariate)},
      {"explained", f.location.explained},
      {"windows", windows}};
  if (f.significant) {
    out["profile"] = ProfileJson(f.profile);
    for (const std::string& plot : plots) {
      if (fs::path(plot).filename() == PlotName(f)) out["plot"] = plot;
    }
  }
  return out;
}

}  // namespace

nlohmann::ordered_json BearingDiagnosisJson(const BearingDiagnosis& diagnosis,
                                            const std::string& input,
                                            const std::vector<std::string>& plots) {
  nlohmann::ordered_json out;
  out["problem"] = "bearing";
  out["input"] = input;
  out["samples"] = diagnosis.samples;
  out["units"] = "m, rad, s; eta and xi in 1/m";
  out["baseline"] = FitJson(diagnosis.baseline);
  nlohmann::ordered_json findings = nlohmann::ordered_json::array();
  for (const BearingFinding& f : diagnosis.findings) findings.push_back(FindingJson(f, plots));
  out["findings"] = findings;
  out["final"] = FitJson(diagnosis.final_fit);
  out["residual_structure"] = {{"before", StructureJson(diagnosis.structure_before)},
                               {"after", StructureJson(diagnosis.structure_after)}};
  nlohmann::ordered_json profiles = nlohmann::ordered_json::array();
  for (const CovariateProfile& profile : diagnosis.covariates) {
    profiles.push_back(ProfileJson(profile));
  }
  out["figures"] = {{"rms_before", {diagnosis.baseline.rms_rad}},
                    {"rms_after", {diagnosis.final_fit.rms_rad}},
                    {"robust_cost_before", diagnosis.baseline.robust_cost},
                    {"robust_cost_after", diagnosis.final_fit.robust_cost},
                    {"covariates", profiles},
                    {"plots", plots}};
  out["noise"] = {{"bearing_sigma_rad", diagnosis.base.noise.bearing_sigma_rad},
                  {"encoder_k", diagnosis.base.noise.encoder_k}};
  out["notes"] = diagnosis.notes;
  out["seconds"] = diagnosis.seconds;
  return out;
}

std::string BearingDiagnosisSummary(const BearingDiagnosis& diagnosis, const std::string& input,
                                    const std::vector<std::string>& plots) {
  std::string text;
  char line[512];
  std::snprintf(line, sizeof(line), "%s: bearing-only diagnosis, %d bearings\n", input.c_str(),
                diagnosis.samples);
  text += line;
  text += "  adopted effects: " +
          (diagnosis.adopted.empty() ? std::string("none") : diagnosis.adopted.front()) + "\n";
  for (const BearingFinding& f : diagnosis.findings) {
    const char* tag =
        f.significant ? "found"
                      : (f.confounded ? "confounded" : (f.no_information ? "unseen" : "not found"));
    text += "  [" + std::string(tag) + "] " + f.statement + "\n";
  }
  std::snprintf(line, sizeof(line), "  %-12s %12s %10s %12s %10s %8s\n", "parameter", "baseline",
                "± σ", "final", "± σ", "shift/σ");
  text += line;
  const BearingParamVector before = ToVector(diagnosis.baseline.estimate);
  const BearingParamVector after = ToVector(diagnosis.final_fit.estimate);
  for (int i = 0; i < kNumBearingParams; ++i) {
    const bool angle = i == kBearingPhi || i == kBearingPsi;
    const double k = angle ? 180.0 / M_PI : 1.0;
    const std::string name = std::string(kBearingParamNames[i]) + (angle ? " [deg]" : "");
    const double sigma = diagnosis.baseline.stddev(i);
    std::snprintf(line, sizeof(line), "  %-12s %12.5f %10.5f %12.5f %10.5f %8.2f\n", name.c_str(),
                  before(i) * k, sigma * k, after(i) * k, diagnosis.final_fit.stddev(i) * k,
                  sigma > 0.0 ? (after(i) - before(i)) / sigma : 0.0);
    text += line;
  }
  std::snprintf(line, sizeof(line), "  bearing RMS of the inliers: before %.4f°, after %.4f°\n",
                diagnosis.baseline.rms_rad * 180.0 / M_PI,
                diagnosis.final_fit.rms_rad * 180.0 / M_PI);
  text += line;
  text += "  residuals before: " + diagnosis.structure_before.statement + "\n";
  text += "  residuals after:  " + diagnosis.structure_after.statement + "\n";
  for (const std::string& note : diagnosis.notes) text += "  note: " + note + "\n";
  for (const std::string& plot : plots) text += "  plot: " + plot + "\n";
  return text;
}

StatusOr<std::vector<std::string>> WriteBearingDiagnosisPlots(const BearingDiagnosis& diagnosis,
                                                              const std::string& directory) {
  PlotFiles files;
  for (const BearingFinding& f : diagnosis.findings) {
    if (!f.significant) continue;
    files.emplace_back(PlotName(f),
                       CovariateProfileSvg(f.profile, f.name + ": bearing residuals against " +
                                                          f.location.covariate));
  }
  AddResidualPlots(diagnosis.covariates, diagnosis.structure_before, diagnosis.structure_after,
                   "bearing residuals", &files);
  return WritePlotFiles(directory, files);
}

}  // namespace calib
