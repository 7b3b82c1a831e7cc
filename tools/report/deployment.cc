#include <calib/tools/report/deployment.h>
#include <calib/tools/report/json_output.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace calib {
namespace {

struct YawPitchRoll {
  double yaw = 0.0, pitch = 0.0, roll = 0.0;
};

// R = Rz(yaw)·Ry(pitch)·Rx(roll), the order of tf's static_transform_publisher and URDF's rpy.
YawPitchRoll Angles(const Eigen::Matrix3d& r) {
  YawPitchRoll a;
  a.yaw = std::atan2(r(1, 0), r(0, 0));
  a.pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  a.roll = std::atan2(r(2, 1), r(2, 2));
  return a;
}

std::string Format(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

std::string Number(double value) { return Format("%.6f", value == 0.0 ? 0.0 : value); }

std::string Quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

double MeanRadius(const Deployment& d) {
  return 0.5 * (d.left_wheel_radius_m + d.right_wheel_radius_m);
}

std::string Sigma(double stddev, const char* unit) {
  return stddev > 0.0 ? "  # ± " + Format("%.6f", stddev) + " " + unit + " (1σ)" : "";
}

std::string MountingYaml(const Deployment& d) {
  const Eigen::Vector3d t = d.base_T_sensor.translation();
  const YawPitchRoll a = Angles(d.base_T_sensor.linear());
  const char* height = d.sensor_height_from_tf ? "  # from tf, not calibrated"
                                               : "  # unknown to a planar calibration: set it";
  std::string out = "sensor_mounting:\n";
  out += "  parent_frame: " + Quoted(d.base_frame) + "\n";
  out += "  child_frame: " + Quoted(d.sensor_frame) + "\n";
  out += "  x: " + Number(t.x()) + Sigma(d.sensor_x_stddev_m, "m") + "\n";
  out += "  y: " + Number(t.y()) + Sigma(d.sensor_y_stddev_m, "m") + "\n";
  out += "  z: " + Number(t.z()) + height + "\n";
  out += "  yaw: " + Number(a.yaw) + Sigma(d.sensor_yaw_stddev_rad, "rad") + "\n";
  out += "  pitch: " + Number(a.pitch) + height + "\n";
  out += "  roll: " + Number(a.roll) + height + "\n";
  return out;
}

std::string Stem(const std::string& output) {
  if (output.empty() || output == "-") return "calib_calibration";
  const std::filesystem::path path(output);
  // Nothing is written beside a device or a pipe (/dev/stdout): the working directory instead.
  std::error_code error;
  if (std::filesystem::exists(path, error) && !std::filesystem::is_regular_file(path, error)) {
    return "calib_calibration";
  }
  return (path.parent_path() / path.stem()).string();
}

}  // namespace

StatusOr<std::vector<std::string>> ParseExportFormats(const std::string& formats) {
  std::vector<std::string> out;
  std::stringstream stream(formats);
  std::string part;
  while (std::getline(stream, part, ',')) {
    if (part.empty()) continue;
    if (part == "all") {
      out = {"yaml", "urdf", "tf"};
      continue;
    }
    if (part != "yaml" && part != "urdf" && part != "tf") {
      return Status::InvalidInput("unknown --export '" + part + "' (yaml, urdf, tf or all)");
    }
    if (std::find(out.begin(), out.end(), part) == out.end()) out.push_back(part);
  }
  return out;
}

std::string DeploymentYaml(const Deployment& d) {
  const double r = MeanRadius(d);
  std::string out = "# calib calibration of " + d.source + " (m, rad, s).\n";
  out += "wheel_radius: " + Number(r) + "  # mean of the two wheels\n";
  out += "left_wheel_radius: " + Number(d.left_wheel_radius_m) +
         Sigma(d.left_wheel_radius_stddev_m, "m") + "\n";
  out += "right_wheel_radius: " + Number(d.right_wheel_radius_m) +
         Sigma(d.right_wheel_radius_stddev_m, "m") + "\n";
  out += "wheel_separation: " + Number(d.wheel_separation_m) +
         Sigma(d.wheel_separation_stddev_m, "m") + "\n";
  out += MountingYaml(d);
  if (d.time_offset_s) {
    out += "sensor_time_offset: " + Number(*d.time_offset_s) +
           "  # s: add to the sensor's stamps (odometry clock)" +
           (d.time_offset_stddev_s > 0.0 ? ", ± " + Format("%.6f", d.time_offset_stddev_s) : "") +
           "\n";
  }
  // ros2_control's diff_drive_controller: each wheel's radius is wheel_radius × its multiplier.
  out += "diff_drive_controller:\n  ros__parameters:\n";
  out += "    wheel_separation: " + Number(d.wheel_separation_m) + "\n";
  out += "    wheel_radius: " + Number(r) + "\n";
  out += "    wheel_separation_multiplier: 1.0\n";
  out += "    left_wheel_radius_multiplier: " + Number(d.left_wheel_radius_m / r) + "\n";
  out += "    right_wheel_radius_multiplier: " + Number(d.right_wheel_radius_m / r) + "\n";
  if (!d.notes.empty()) {
    out += "notes:\n";
    for (const std::string& note : d.notes) out += "  - " + Quoted(note) + "\n";
  }
  return out;
}

std::string DeploymentUrdf(const Deployment& d) {
  const Eigen::Vector3d t = d.base_T_sensor.translation();
  const YawPitchRoll a = Angles(d.base_T_sensor.linear());
  std::string out =
      "<!-- calib calibration of " + d.source +
      ": the sensor's mounting (x, y, yaw calibrated; z, roll, pitch " +
      (d.sensor_height_from_tf ? "from tf" : "unknown to a planar calibration, 0: set them") +
      "). Wheels: " + "left radius " + Number(d.left_wheel_radius_m) + " m, right radius " +
      Number(d.right_wheel_radius_m) + " m, separation " + Number(d.wheel_separation_m) +
      " m. -->\n";
  out += "<joint name=\"" + d.sensor_frame + "_joint\" type=\"fixed\">\n";
  out += "  <parent link=\"" + d.base_frame + "\"/>\n";
  out += "  <child link=\"" + d.sensor_frame + "\"/>\n";
  out += "  <origin xyz=\"" + Number(t.x()) + " " + Number(t.y()) + " " + Number(t.z()) +
         "\" rpy=\"" + Number(a.roll) + " " + Number(a.pitch) + " " + Number(a.yaw) + "\"/>\n";
  return out + "</joint>\n";
}

std::string DeploymentStaticTransform(const Deployment& d) {
  const Eigen::Vector3d t = d.base_T_sensor.translation();
  const YawPitchRoll a = Angles(d.base_T_sensor.linear());
  return Number(t.x()) + " " + Number(t.y()) + " " + Number(t.z()) + " " + Number(a.yaw) + " " +
         Number(a.pitch) + " " + Number(a.roll) + " " + d.base_frame + " " + d.sensor_frame + "\n";
}

StatusOr<std::vector<std::string>> WriteDeployment(const Deployment& deployment,
                                                   const std::vector<std::string>& formats,
                                                   const std::string& output) {
  std::vector<std::string> paths;
  const std::string stem = Stem(output);
  for (const std::string& format : formats) {
    const std::string path = stem + "." + format;
    const std::string text = format == "yaml"   ? DeploymentYaml(deployment)
                             : format == "urdf" ? DeploymentUrdf(deployment)
                                                : DeploymentStaticTransform(deployment);
    CALIB_RETURN_IF_ERROR(WriteTextFile(path, text));
    paths.push_back(path);
  }
  return paths;
}

}  // namespace calib
