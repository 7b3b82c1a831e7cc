#include <calib/tools/report/deploy_advice.h>

#include <cstdio>
#include <map>
#include <vector>

namespace calib {
namespace {

// What a standard controller cannot do about each physical effect.
const std::map<std::string, std::string>& Inexpressible() {
  static const std::map<std::string, std::string> words = {
      {"lateral_slip", "the robot slides sideways in turns (lateral slip)"},
      {"longitudinal_slip", "the wheels slip when the robot accelerates (longitudinal slip)"},
      {"speed_dependent_radius", "the wheels' effective radius changes with speed"},
      {"icr_offset_x", "the robot turns about a point off its wheel axle"},
      {"scan_scale", "the sensor's distances are scaled"}};
  return words;
}

bool IsTiming(const std::string& effect) {
  return effect == "sample_times" || effect == "stamp_jitter";
}

const nlohmann::ordered_json* Finding(const nlohmann::ordered_json& diagnosis,
                                      const std::string& effect) {
  for (const auto& f : diagnosis["findings"]) {
    if (f.value("effect", "") == effect) return &f;
  }
  return nullptr;
}

}  // namespace

DeployAdvice AdviseDeployment(const nlohmann::ordered_json& diagnosis) {
  DeployAdvice advice;
  nlohmann::ordered_json& out = advice.json;
  const nlohmann::ordered_json& final_fit = diagnosis["final"];
  out["estimate"] = final_fit["estimate"];
  std::string statement = "the final estimate";
  std::vector<std::string> physical, cannot;
  for (const auto& e : final_fit["effects"]) {
    if (!IsTiming(e.get<std::string>())) physical.push_back(e.get<std::string>());
  }
  if (physical.empty()) {
    statement += " (no physical effect adopted: it is the calibration itself";
    statement += final_fit["effects"].empty() ? ")" : ", with the timing modelled)";
  } else {
    statement += " (its parameters are not biased by the adopted effects)";
  }
  for (const std::string& effect : physical) {
    const nlohmann::ordered_json* f = Finding(diagnosis, effect);
    if (effect == "wheel_radius_change" && f != nullptr && f->contains("r_l_after")) {
      out["estimate"]["r_l"] = (*f)["r_l_after"];
      out["estimate"]["r_r"] = (*f)["r_r_after"];
      statement += ", with the wheel radii after the change (the wheels as they are now)";
    } else if (effect == "time_offset" && f != nullptr && f->contains("value")) {
      out["sensor_time_offset_s"] = (*f)["value"];
      char text[96];
      std::snprintf(text, sizeof(text), "; set the sensor driver's time offset to %+.4f s",
                    (*f)["value"].get<double>());
      statement += text;
    } else if (Inexpressible().count(effect)) {
      cannot.push_back(effect);
    }
  }
  out["not_expressible"] = cannot;
  std::string summary = "  deploy: " + statement + "\n";
  for (const std::string& effect : cannot) {
    summary += "  deploy: a standard diff_drive_controller cannot express that " +
               Inexpressible().at(effect) +
               ": its odometry will drift where this acts, whatever the parameters\n";
  }
  out["statement"] = statement;
  advice.summary = summary;
  return advice;
}

}  // namespace calib
