#include <calib/tools/report/laser_diagnose_report.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <calib/core/laser/laser_log_io.h>
#include <calib/tools/report/bearing_diagnose_report.h>
#include <calib/tools/report/bearing_report.h>

namespace calib {
namespace {

namespace fs = std::filesystem;

nlohmann::ordered_json Number(double x) {
  if (!std::isfinite(x)) return nullptr;
  return x;
}

nlohmann::ordered_json ParamObject(const LaserParamVector& v) {
  nlohmann::ordered_json object;
  for (int i = 0; i < kNumLaserParams; ++i) object[kLaserParamNames[i]] = Number(v(i));
  return object;
}

nlohmann::ordered_json Vector(const Eigen::VectorXd& v) {
  nlohmann::ordered_json array = nlohmann::ordered_json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) array.push_back(Number(v(i)));
  return array;
}

std::string BoundaryName(BoundarySpeedModel model) {
  return model == BoundarySpeedModel::kSmooth ? "smooth" : "piecewise_constant";
}

nlohmann::ordered_json FitJson(const LaserFitReport& fit) {
  nlohmann::ordered_json out;
  nlohmann::ordered_json effects = nlohmann::ordered_json::array();
  for (LaserEffect effect : fit.effects) effects.push_back(LaserEffectName(effect));
  out["effects"] = effects;
  out["estimate"] = ParamObject(fit.estimate.ToVector());
  out["stddev"] = ParamObject(fit.stddev);
  out["rms"] = {fit.rms(0), fit.rms(1), fit.rms(2)};
  out["rms_units"] = {"m", "m", "rad"};
  out["robust_cost"] = fit.robust_cost;
  out["inliers"] = fit.inliers;
  nlohmann::ordered_json values;
  for (LaserEffect effect : fit.effects) {
    const LaserEffectInfo& info = EffectInfo(effect);
    nlohmann::ordered_json value;
    if (effect == LaserEffect::kWheelRadiusChange) {
      value["value"] = fit.change_time_s;
      value["stddev"] = Number(fit.change_time_stddev_s);
      value["unit"] = "s";
      value["gamma"] = {fit.gamma(info.offset), fit.gamma(info.offset + 1)};
      value["gamma_stddev"] = {fit.gamma_stddev(info.offset), fit.gamma_stddev(info.offset + 1)};
    } else {
      value["value"] = fit.gamma(info.offset);
      value["stddev"] = Number(fit.gamma_stddev(info.offset));
      value["unit"] = info.unit;
    }
    values[info.name] = value;
  }
  out["effect_values"] = values;
  out["boundary_speeds"] = BoundaryName(fit.boundary);
  return out;
}

}  // namespace

nlohmann::ordered_json ProfileJson(const CovariateProfile& profile) {
  nlohmann::ordered_json out;
  out["covariate"] = profile.name;
  out["unit"] = profile.unit;
  out["center"] = profile.center;
  const auto rows = [](const std::vector<Eigen::VectorXd>& values) {
    nlohmann::ordered_json array = nlohmann::ordered_json::array();
    for (const Eigen::VectorXd& v : values) array.push_back(Vector(v));
    return array;
  };
  const Eigen::Index channels = profile.before_mean.empty() ? 0 : profile.before_mean[0].size();
  if (!profile.channel_labels.empty()) {
    out["channels"] = channels == 1
                          ? nlohmann::ordered_json({"bearing [rad]"})
                          : nlohmann::ordered_json({"bearing [rad]", "along the effect [sigma]"});
  } else {
    out["channels"] =
        channels == 0 || channels == 3
            ? nlohmann::ordered_json({"x [m]", "y [m]", "theta [rad]"})
            : nlohmann::ordered_json({"x [m]", "y [m]", "theta [rad]", "along the effect [sigma]"});
  }
  out["before_mean"] = rows(profile.before_mean);
  out["before_stderr"] = rows(profile.before_stderr);
  out["after_mean"] = rows(profile.after_mean);
  out["after_stderr"] = rows(profile.after_stderr);
  out["before_p_value"] = profile.before_p_value;
  out["after_p_value"] = profile.after_p_value;
  return out;
}

nlohmann::ordered_json StructureJson(const ResidualStructure& structure) {
  nlohmann::ordered_json out;
  out["found"] = structure.found;
  out["covariate"] = structure.covariate.empty() ? nlohmann::ordered_json(nullptr)
                                                 : nlohmann::ordered_json(structure.covariate);
  out["p_value"] = structure.p_value;
  out["change_time_s"] = structure.change_time_s >= 0.0 ? Number(structure.change_time_s)
                                                        : nlohmann::ordered_json(nullptr);
  out["change_p_value"] = structure.change_p_value;
  out["statement"] = structure.statement;
  return out;
}

namespace {

std::string PlotName(const LaserFinding& finding) {
  return finding.name + "_vs_" + finding.location.covariate + ".svg";
}

nlohmann::ordered_json FindingJson(const LaserFinding& f, const std::vector<std::string>& plots) {
  nlohmann::ordered_json out;
  out["effect"] = f.name;
  out["significant"] = f.significant;
  const bool unknowable = f.confounded || f.no_information;
  out["value"] = unknowable ? nlohmann::ordered_json(nullptr) : Number(f.value);
  out["stddev"] = unknowable ? nlohmann::ordered_json(nullptr) : Number(f.stddev);
  out["unit"] = f.unit;
  out["statement"] = f.statement;
  if (f.confounded) out["confounded_with"] = f.confounded_with;
  if (f.no_information) out["no_information"] = true;
  if (f.effect == LaserEffect::kWheelRadiusChange && !unknowable) {
    out["r_l_after"] = f.r_l_after;
    out["r_r_after"] = f.r_r_after;
    out["r_l_after_stddev"] = Number(f.r_l_after_stddev);
    out["r_r_after_stddev"] = Number(f.r_r_after_stddev);
  }
  out["concealment"] = Number(f.concealment);
  if (!unknowable) {
    out["score_test"] = {
        {"step", f.step},       {"statistic", f.statistic},   {"dof", f.dof},
        {"p_value", f.p_value}, {"holm_level", f.holm_level}, {"significant", f.score_significant}};
    out["one_step"] = {{"gamma", Vector(f.one_step)}, {"stddev", Vector(f.one_step_stddev)}};
    out["absorbed_by_base"] = ParamObject(f.absorbed);
  }
  if (f.refitted) {
    out["likelihood_ratio"] = {{"statistic", f.lr_statistic},
                               {"p_value", f.lr_p_value},
                               {"delta_aic", f.delta_aic},
                               {"delta_bic", f.delta_bic}};
    out["held_out"] = {{"cost_before", f.heldout_cost_before},
                       {"cost_after", f.heldout_cost_after},
                       {"reduction", f.heldout_reduction},
                       {"rms_before", f.heldout_rms_before},
                       {"rms_after", f.heldout_rms_after}};
  }
  if (f.significant) {
    nlohmann::ordered_json shift;
    for (int i = 0; i < kNumLaserParams; ++i) {
      shift[kLaserParamNames[i]] = {{"value", f.base_shift(i)}, {"sigmas", f.base_shift_sigmas(i)}};
    }
    out["base_shift"] = shift;
    out["absorbed_share"] = f.absorbed_share;
    nlohmann::ordered_json windows = nlohmann::ordered_json::array();
    for (const MismatchLocation::Window& w : f.location.windows) {
      windows.push_back(
          {{"start_s", w.start_s}, {"end_s", w.end_s}, {"share", w.share}, {"rate", w.rate}});
    }
    out["location"] = {{"covariate", f.location.covariate},
                       {"explained", f.location.explained},
                       {"windows", windows}};
    out["figure"] = ProfileJson(f.profile);
    for (const std::string& plot : plots) {
      if (plot.size() >= PlotName(f).size() &&
          plot.compare(plot.size() - PlotName(f).size(), PlotName(f).size(), PlotName(f)) == 0) {
        out["plot"] = plot;
      }
    }
  }
  return out;
}

// --- SVG -----------------------------------------------------------------------------------

// Round tick positions covering [lo, hi].
std::vector<double> Ticks(double lo, double hi) {
  const double range = hi - lo;
  if (!(range > 0.0)) return {lo};
  const double raw = range / 5.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = magnitude;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * magnitude;
    if (step >= raw) break;
  }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) {
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  }
  return ticks;
}

std::string TickLabel(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", v);
  return text;
}

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (c == '&') {
      out += "&amp;";
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

std::string CovariateProfileSvg(const CovariateProfile& profile, const std::string& title) {
  const int channels =
      profile.before_mean.empty() ? 0 : static_cast<int>(profile.before_mean[0].size());
  std::vector<std::string> labels = {"x error [mm]", "y error [mm]", "θ error [mrad]",
                                     "along the effect [σ]"};
  std::vector<double> scales = {1e3, 1e3, 1e3, 1.0};
  if (!profile.channel_labels.empty()) {
    labels = profile.channel_labels;
    scales = profile.channel_scales;
  }
  const int columns = 2, rows = (channels + 1) / 2;
  const double panel_w = 430, panel_h = 250, left = 70, top = 84, gap_x = 40, gap_y = 84;
  const double width = left + columns * (panel_w + gap_x),
               height = top + rows * (panel_h + gap_y) + 20;
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  svg << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  svg << "<text x=\"" << left << "\" y=\"24\" font-size=\"16\">" << Escape(title) << "</text>\n";
  svg << "<text x=\"" << left << "\" y=\"46\" fill=\"#d95f02\">● before (base model)</text>";
  svg << "<text x=\"" << left + 170
      << "\" y=\"46\" fill=\"#1b7837\">■ after (with the adopted "
         "effects)</text>";
  svg << "<text x=\"" << left + 460
      << "\" y=\"46\" fill=\"#555\">binned means ± 2 standard "
         "errors</text>\n";
  const size_t bins = profile.center.size();
  if (bins == 0 || channels == 0) {
    svg << "</svg>\n";
    return svg.str();
  }
  // Bins hold equal counts, so they are drawn at equal spacing (the covariate's quantiles) and
  // labelled with their mean covariate.
  const auto px_of = [&](double ox, double b) { return ox + (b + 0.5) / bins * panel_w; };
  for (int c = 0; c < channels; ++c) {
    const double ox = left + (c % columns) * (panel_w + gap_x);
    const double oy = top + (c / columns) * (panel_h + gap_y);
    double y_lo = 0.0, y_hi = 0.0;
    for (size_t b = 0; b < bins; ++b) {
      for (const auto* series : {&profile.before_mean, &profile.after_mean}) {
        const auto& stderrs =
            series == &profile.before_mean ? profile.before_stderr : profile.after_stderr;
        if (b >= series->size()) continue;
        const double m = (*series)[b](c) * scales[c], e = 2.0 * stderrs[b](c) * scales[c];
        y_lo = std::min(y_lo, m - e);
        y_hi = std::max(y_hi, m + e);
      }
    }
    if (!(y_hi > y_lo)) y_hi = y_lo + 1.0;
    const double pad = 0.05 * (y_hi - y_lo);
    y_lo -= pad;
    y_hi += pad;
    const auto py = [&](double y) { return oy + panel_h - (y - y_lo) / (y_hi - y_lo) * panel_h; };
    svg << "<rect x=\"" << ox << "\" y=\"" << oy << "\" width=\"" << panel_w << "\" height=\""
        << panel_h << "\" fill=\"none\" stroke=\"#888\"/>\n";
    for (double t : Ticks(y_lo, y_hi)) {
      svg << "<line x1=\"" << ox << "\" x2=\"" << ox + panel_w << "\" y1=\"" << py(t) << "\" y2=\""
          << py(t) << "\" stroke=\"" << (t == 0.0 ? "#444" : "#eee") << "\"/>";
      svg << "<text x=\"" << ox - 6 << "\" y=\"" << py(t) + 4 << "\" text-anchor=\"end\">"
          << TickLabel(t) << "</text>\n";
    }
    for (size_t b = 0; b < bins; ++b) {
      const double x = px_of(ox, b);
      char label[32];
      std::snprintf(label, sizeof(label), "%.2g", profile.center[b]);
      svg << "<line x1=\"" << x << "\" x2=\"" << x << "\" y1=\"" << oy + panel_h << "\" y2=\""
          << oy + panel_h + 4 << "\" stroke=\"#888\"/>";
      svg << "<text font-size=\"10\" text-anchor=\"end\" transform=\"translate(" << x + 3 << ","
          << oy + panel_h + 12 << ") rotate(-35)\">" << label << "</text>\n";
    }
    svg << "<text x=\"" << ox + panel_w / 2 << "\" y=\"" << oy - 8 << "\" text-anchor=\"middle\">"
        << labels[c] << "</text>\n";
    svg << "<text x=\"" << ox + panel_w / 2 << "\" y=\"" << oy + panel_h + 48
        << "\" text-anchor=\"middle\" fill=\"#555\">" << Escape(profile.name) << " ["
        << Escape(profile.unit) << "], bins of equal count</text>\n";
    const auto series = [&](const std::vector<Eigen::VectorXd>& means,
                            const std::vector<Eigen::VectorXd>& stderrs, const char* colour,
                            bool square, double shift) {
      std::ostringstream line;
      for (size_t b = 0; b < means.size() && b < bins; ++b) {
        const double x = px_of(ox, b) + shift;
        const double m = means[b](c) * scales[c], e = 2.0 * stderrs[b](c) * scales[c];
        line << (b ? " " : "") << x << "," << py(m);
        svg << "<line x1=\"" << x << "\" x2=\"" << x << "\" y1=\"" << py(m - e) << "\" y2=\""
            << py(m + e) << "\" stroke=\"" << colour << "\"/>";
        if (square) {
          svg << "<rect x=\"" << x - 3.5 << "\" y=\"" << py(m) - 3.5
              << "\" width=\"7\" height=\"7\" fill=\"" << colour << "\"/>";
        } else {
          svg << "<circle cx=\"" << x << "\" cy=\"" << py(m) << "\" r=\"4\" fill=\"" << colour
              << "\"/>";
        }
      }
      svg << "\n<polyline points=\"" << line.str() << "\" fill=\"none\" stroke=\"" << colour
          << "\" stroke-width=\"1.2\"/>\n";
    };
    series(profile.before_mean, profile.before_stderr, "#d95f02", false, -2.0);
    series(profile.after_mean, profile.after_stderr, "#1b7837", true, 2.0);
  }
  svg << "</svg>\n";
  return svg.str();
}

StatusOr<std::vector<std::string>> WritePlotFiles(const std::string& directory,
                                                  const PlotFiles& files) {
  std::error_code error;
  fs::create_directories(directory, error);
  if (error) {
    return Status::Error("cannot create the plot folder " + directory + ": " + error.message());
  }
  std::vector<std::string> written;
  for (const auto& [name, svg] : files) {
    const std::string path = (fs::path(directory) / name).string();
    std::ofstream out(path);
    out << svg;
    if (!out) return Status::Error("cannot write " + path);
    written.push_back(path);
  }
  return written;
}

void AddResidualPlots(const std::vector<CovariateProfile>& covariates,
                      const ResidualStructure& before, const ResidualStructure& after,
                      const std::string& title, PlotFiles* files) {
  for (const CovariateProfile& profile : covariates) {
    if (profile.name != "time" && profile.name != before.covariate &&
        profile.name != after.covariate) {
      continue;
    }
    files->emplace_back("residuals_vs_" + profile.name + ".svg",
                        CovariateProfileSvg(profile, title + " against " + profile.name));
  }
}

StatusOr<std::vector<std::string>> WriteLaserDiagnosisPlots(const LaserDiagnosis& diagnosis,
                                                            const std::string& directory) {
  PlotFiles files;
  for (const LaserFinding& f : diagnosis.findings) {
    if (!f.significant) continue;
    files.emplace_back(PlotName(f), CovariateProfileSvg(f.profile, f.name + ": residuals against " +
                                                                       f.location.covariate));
  }
  AddResidualPlots(diagnosis.covariates, diagnosis.structure_before, diagnosis.structure_after,
                   "residuals", &files);
  return WritePlotFiles(directory, files);
}

nlohmann::ordered_json LaserDiagnosisJson(const LaserDiagnosis& diagnosis, const std::string& input,
                                          const std::vector<std::string>& plots) {
  nlohmann::ordered_json out;
  out["problem"] = "laser";
  out["input"] = input;
  out["samples"] = diagnosis.samples;
  out["units"] = "m, rad, s";
  out["baseline"] = FitJson(diagnosis.baseline);
  nlohmann::ordered_json findings = nlohmann::ordered_json::array();
  for (const LaserFinding& f : diagnosis.findings) findings.push_back(FindingJson(f, plots));
  out["findings"] = findings;
  out["final"] = FitJson(diagnosis.final_fit);
  out["residual_structure"] = {{"before", StructureJson(diagnosis.structure_before)},
                               {"after", StructureJson(diagnosis.structure_after)}};
  nlohmann::ordered_json profiles = nlohmann::ordered_json::array();
  for (const CovariateProfile& profile : diagnosis.covariates) {
    profiles.push_back(ProfileJson(profile));
  }
  out["figures"] = {
      {"rms_before",
       {diagnosis.baseline.rms(0), diagnosis.baseline.rms(1), diagnosis.baseline.rms(2)}},
      {"rms_after",
       {diagnosis.final_fit.rms(0), diagnosis.final_fit.rms(1), diagnosis.final_fit.rms(2)}},
      {"robust_cost_before", diagnosis.baseline.robust_cost},
      {"robust_cost_after", diagnosis.final_fit.robust_cost},
      {"covariates", profiles},
      {"plots", plots}};
  out["notes"] = diagnosis.notes;
  out["steps"] = diagnosis.steps;
  out["seconds"] = diagnosis.seconds;
  return out;
}

std::string LaserDiagnosisSummary(const LaserDiagnosis& diagnosis, const std::string& input,
                                  const std::vector<std::string>& plots) {
  std::string text;
  char line[512];
  std::snprintf(line, sizeof(line), "%s: laser–odometry diagnosis, %d intervals\n", input.c_str(),
                diagnosis.samples);
  text += line;
  std::string adopted;
  for (LaserEffect effect : diagnosis.adopted) {
    adopted += (adopted.empty() ? "" : ", ") + LaserEffectName(effect);
  }
  text += "  adopted effects: " + (adopted.empty() ? std::string("none") : adopted) + "\n";
  for (const LaserFinding& f : diagnosis.findings) {
    const char* tag =
        f.significant ? "found"
                      : (f.confounded ? "confounded" : (f.no_information ? "unseen" : "not found"));
    text += "  [" + std::string(tag) + "] " + f.statement + "\n";
  }
  std::snprintf(line, sizeof(line), "  %-14s %12s %10s %12s %10s %8s\n", "parameter", "baseline",
                "± σ", "final", "± σ", "shift/σ");
  text += line;
  const LaserParamVector before = diagnosis.baseline.estimate.ToVector();
  const LaserParamVector after = diagnosis.final_fit.estimate.ToVector();
  for (int i = 0; i < kNumLaserParams; ++i) {
    const double k = i == 5 ? 180.0 / M_PI : 1000.0;
    const std::string name = kLaserParamNames[i] + (i == 5 ? " [deg]" : " [mm]");
    const double sigma = diagnosis.baseline.stddev(i);
    std::snprintf(line, sizeof(line), "  %-14s %12.4f %10.4f %12.4f %10.4f %8.2f\n", name.c_str(),
                  before(i) * k, sigma * k, after(i) * k, diagnosis.final_fit.stddev(i) * k,
                  sigma > 0.0 ? (after(i) - before(i)) / sigma : 0.0);
    text += line;
  }
  std::snprintf(line, sizeof(line),
                "  residual RMS of the inliers (x mm, y mm, θ mrad): before %.3f %.3f %.3f, after "
                "%.3f %.3f %.3f\n",
                diagnosis.baseline.rms(0) * 1e3, diagnosis.baseline.rms(1) * 1e3,
                diagnosis.baseline.rms(2) * 1e3, diagnosis.final_fit.rms(0) * 1e3,
                diagnosis.final_fit.rms(1) * 1e3, diagnosis.final_fit.rms(2) * 1e3);
  text += line;
  text += "  residuals before: " + diagnosis.structure_before.statement + "\n";
  text += "  residuals after:  " + diagnosis.structure_after.statement + "\n";
  for (const std::string& note : diagnosis.notes) text += "  note: " + note + "\n";
  for (const std::string& plot : plots) text += "  plot: " + plot + "\n";
  return text;
}

}  // namespace calib
