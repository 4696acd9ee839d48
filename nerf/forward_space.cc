#include "nerf/forward_space.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace p2n {
namespace {

constexpr double kNearShare = 0.8;  // the near plane, as a share of the nearest scene depth seen

Eigen::Vector3d Axis(const PinholeCamera& camera) { return -camera.world_from_cam.block<3, 1>(0, 2); }

double Finite(const nlohmann::json& json, const char* key) {
  const double value = json.at(key).get<double>();
  if (!std::isfinite(value)) throw std::invalid_argument(std::string("forward frame: ") + key + " is not finite");
  return value;
}

}  // namespace

Eigen::Vector3d ForwardNdc(const ForwardFrame& frame, const Eigen::Vector3d& world) {
  const Eigen::Vector3d p = frame.cam_from_world * (world - frame.centre);
  const double depth = -p.z();
  if (!(depth > 0)) return Eigen::Vector3d(0, 0, -2);
  return Eigen::Vector3d(p.x() / (depth * frame.tan_x), p.y() / (depth * frame.tan_y), 1 - 2 * frame.near / depth);
}

Eigen::Matrix3d ForwardNdcJacobian(const ForwardFrame& frame, const Eigen::Vector3d& world) {
  const Eigen::Vector3d p = frame.cam_from_world * (world - frame.centre);
  const double depth = -p.z();
  if (!(depth > 0)) return Eigen::Matrix3d::Zero();
  Eigen::Matrix3d by_camera_point;  // rows: x', y', z'; depth = -p.z
  by_camera_point << 1 / (depth * frame.tan_x), 0, p.x() / (frame.tan_x * depth * depth),  //
      0, 1 / (depth * frame.tan_y), p.y() / (frame.tan_y * depth * depth),                 //
      0, 0, -2 * frame.near / (depth * depth);
  return by_camera_point * frame.cam_from_world;
}

ForwardRay ToForward(const ForwardFrame& frame, const Ray& ray) {
  ForwardRay out;
  const Eigen::Vector3d origin = frame.cam_from_world * (ray.origin - frame.centre);
  const Eigen::Vector3d direction = frame.cam_from_world * ray.direction;
  out.depth_rate = -direction.z();
  if (!(out.depth_rate > 1e-12) || !origin.allFinite()) return out;
  out.valid = true;
  out.t0 = std::max(0.0, (frame.near - -origin.z()) / out.depth_rate);
  out.depth0 = -origin.z() + out.t0 * out.depth_rate;
  out.start = ForwardNdc(frame, ray.origin + out.t0 * ray.direction);
  out.end = Eigen::Vector3d(direction.x() / (out.depth_rate * frame.tan_x),
                            direction.y() / (out.depth_rate * frame.tan_y), 1);
  return out;
}

ForwardFrame FitForwardFrame(const std::vector<PinholeCamera>& cameras, const std::vector<double>& nears) {
  if (cameras.empty()) throw std::invalid_argument("a forward-facing frame needs at least one camera");
  ForwardFrame frame;
  Eigen::Vector3d up = Eigen::Vector3d::Zero(), axis = Eigen::Vector3d::Zero();
  for (const PinholeCamera& camera : cameras) {
    frame.centre += camera.world_from_cam.block<3, 1>(0, 3) / static_cast<double>(cameras.size());
    up += camera.world_from_cam.block<3, 1>(0, 1);
    axis += Axis(camera);
  }
  axis.normalize();
  const Eigen::Vector3d z = -axis;
  Eigen::Vector3d y = up - up.dot(z) * z;
  if (!(y.norm() > 1e-9)) y = z.unitOrthogonal();
  y.normalize();
  frame.cam_from_world.row(0) = y.cross(z);
  frame.cam_from_world.row(1) = y;
  frame.cam_from_world.row(2) = z;

  double nearest = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < cameras.size() && i < nears.size(); ++i) {
    if (!(nears[i] > 0)) continue;
    const double depth = axis.dot(cameras[i].world_from_cam.block<3, 1>(0, 3) - frame.centre);
    nearest = std::min(nearest, depth + nears[i] * std::max(0.0, Axis(cameras[i]).dot(axis)));
  }
  const double fallback = std::max(0.1 * frame.centre.norm(), 1e-3);
  frame.near = std::isfinite(nearest) && nearest > 0 ? kNearShare * nearest : fallback;

  // Corner rays bound every ray of their camera at every depth (the image of the rectangle at a depth is convex).
  ForwardFrame unit = frame;
  unit.tan_x = unit.tan_y = 1;
  double tan_x = 0, tan_y = 0;
  for (const PinholeCamera& camera : cameras) {
    for (const int corner : {0, 1, 2, 3}) {
      const double u = corner % 2 == 0 ? 0 : camera.width, v = corner < 2 ? 0 : camera.height;
      const ForwardRay ray = ToForward(unit, CameraRay(camera, u, v));
      if (!ray.valid) continue;
      tan_x = std::max({tan_x, std::abs(ray.start.x()), std::abs(ray.end.x())});
      tan_y = std::max({tan_y, std::abs(ray.start.y()), std::abs(ray.end.y())});
    }
  }
  if (!(tan_x > 0 && tan_y > 0 && std::isfinite(tan_x) && std::isfinite(tan_y))) {
    throw std::invalid_argument("no camera looks forward: the scene is not forward-facing");
  }
  frame.tan_x = tan_x;
  frame.tan_y = tan_y;
  return frame;
}

bool FacesForward(const std::vector<PinholeCamera>& cameras, double max_angle_deg) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const PinholeCamera& camera : cameras) mean += Axis(camera);
  if (cameras.empty() || !(mean.norm() > 1e-9)) return false;
  mean.normalize();
  const double min_cosine = std::cos(max_angle_deg * std::numbers::pi / 180);
  return std::all_of(cameras.begin(), cameras.end(),
                     [&](const PinholeCamera& camera) { return Axis(camera).dot(mean) >= min_cosine; });
}

nlohmann::json ForwardFrameJson(const ForwardFrame& frame) {
  nlohmann::json rotation = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation.push_back(frame.cam_from_world(r, c));
  }
  return {{"cam_from_world", rotation},
          {"centre", {frame.centre.x(), frame.centre.y(), frame.centre.z()}},
          {"near", frame.near},
          {"tan_x", frame.tan_x},
          {"tan_y", frame.tan_y}};
}

ForwardFrame ForwardFrameFromJson(const nlohmann::json& json) {
  ForwardFrame frame;
  const std::vector<double> rotation = json.at("cam_from_world").get<std::vector<double>>();
  const std::vector<double> centre = json.at("centre").get<std::vector<double>>();
  if (rotation.size() != 9 || centre.size() != 3) {
    throw std::invalid_argument("forward frame: cam_from_world needs 9 numbers and centre 3");
  }
  for (int k = 0; k < 9; ++k) frame.cam_from_world(k / 3, k % 3) = rotation[k];
  frame.centre = Eigen::Vector3d(centre[0], centre[1], centre[2]);
  const Eigen::Matrix3d r = frame.cam_from_world;
  if (!r.allFinite() || !frame.centre.allFinite() || !(r * r.transpose()).isIdentity(1e-6)) {
    throw std::invalid_argument("forward frame: cam_from_world must be a rotation and centre finite");
  }
  frame.near = Finite(json, "near");
  frame.tan_x = Finite(json, "tan_x");
  frame.tan_y = Finite(json, "tan_y");
  if (!(frame.near > 0 && frame.tan_x > 0 && frame.tan_y > 0)) {
    throw std::invalid_argument("forward frame: near, tan_x and tan_y must be positive");
  }
  return frame;
}

}  // namespace p2n
