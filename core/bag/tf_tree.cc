#include <calib/core/bag/tf_tree.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

namespace calib {
namespace {

std::string Frame(const std::string& name) {
  return !name.empty() && name[0] == '/' ? name.substr(1) : name;
}

struct Edge {
  std::string parent;
  Eigen::Isometry3d parent_T_child = Eigen::Isometry3d::Identity();
};

void AddEdges(const std::vector<TransformStamped>& transforms, std::map<std::string, Edge>* edges) {
  for (const TransformStamped& t : transforms) {
    const std::string child = Frame(t.child_frame);
    if (edges->count(child) || child.empty()) continue;  // The first one of each frame.
    Edge e;
    e.parent = Frame(t.parent_frame);
    e.parent_T_child.translation() = t.translation;
    e.parent_T_child.linear() = t.rotation.normalized().toRotationMatrix();
    (*edges)[child] = e;
  }
}

// The frame and its ancestors, each with ancestor_T_frame; stops at a loop.
std::vector<std::pair<std::string, Eigen::Isometry3d>> Ancestors(
    const std::map<std::string, Edge>& edges, const std::string& frame) {
  std::vector<std::pair<std::string, Eigen::Isometry3d>> out = {
      {frame, Eigen::Isometry3d::Identity()}};
  while (out.size() <= edges.size()) {
    const auto it = edges.find(out.back().first);
    if (it == edges.end()) break;
    out.push_back({it->second.parent, it->second.parent_T_child * out.back().second});
  }
  return out;
}

}  // namespace

StatusOr<PlanarMounting> MountingFromTf(const RobotMessages& bag, const std::string& base_frame,
                                        const std::string& sensor_frame) {
  std::map<std::string, Edge> edges;
  AddEdges(bag.tf_static, &edges);
  AddEdges(bag.tf, &edges);
  const std::string base = Frame(base_frame), sensor = Frame(sensor_frame);
  const auto from_sensor = Ancestors(edges, sensor), from_base = Ancestors(edges, base);
  for (const auto& [ancestor, ancestor_T_sensor] : from_sensor) {
    for (const auto& [other, ancestor_T_base] : from_base) {
      if (other != ancestor) continue;
      const Eigen::Isometry3d base_T_sensor = ancestor_T_base.inverse() * ancestor_T_sensor;
      const Eigen::Matrix3d rotation = base_T_sensor.linear();
      PlanarMounting out;
      const Eigen::Vector3d x_axis = rotation.col(0), z_axis = rotation.col(2);
      out.base_T_sensor_3d = base_T_sensor;
      out.upside_down = z_axis.z() < 0.0;
      out.tilt_rad = std::acos(std::clamp(z_axis.z(), -1.0, 1.0));
      out.base_T_sensor = Pose2d(base_T_sensor.translation().x(), base_T_sensor.translation().y(),
                                 std::atan2(x_axis.y(), x_axis.x()));
      for (const auto& f : from_base) {
        out.chain += (out.chain.empty() ? "" : " → ") + f.first;
        if (f.first == ancestor) break;
      }
      std::vector<std::string> down;
      for (const auto& f : from_sensor) {
        if (f.first == ancestor) break;
        down.insert(down.begin(), f.first);
      }
      for (const std::string& f : down) out.chain += " → " + f;
      return out;
    }
  }
  return Status::InvalidInput(bag.source + ": tf does not connect '" + base + "' and '" + sensor +
                              "' (" + std::to_string(edges.size()) +
                              " frames in tf and tf_static)");
}

}  // namespace calib
