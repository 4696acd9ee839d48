#include "base/camera_path.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

namespace p2n {
namespace {

constexpr double kPi = 3.14159265358979323846;

PinholeCamera WithPose(const PinholeCamera& reference, const Eigen::Matrix4d& world_from_cam) {
  PinholeCamera camera = reference;
  camera.world_from_cam = world_from_cam;
  return camera;
}

void CheckFrames(const CameraPathOptions& options) {
  if (options.frames < 1) throw std::invalid_argument("a camera path needs at least one frame");
}

}  // namespace

std::vector<PinholeCamera> OrbitPath(const PinholeCamera& reference, const CameraPathOptions& options) {
  CheckFrames(options);
  if (!(options.radius > 0)) throw std::invalid_argument("an orbit's radius must be positive");
  std::vector<PinholeCamera> path;
  const double elevation = options.elevation_deg * kPi / 180;
  if (!(options.sweep_deg > 0)) throw std::invalid_argument("an orbit's sweep must be positive");
  const bool round = options.sweep_deg >= 360;
  for (int i = 0; i < options.frames; ++i) {
    // An arc's way back passes the cameras of the way there exactly (frame frames - i is frame i), so that the
    // render stage draws each of them once.
    const double phase = 2 * kPi * (round ? i : std::min(i, options.frames - i)) / options.frames;
    const double sweep = round ? phase : options.sweep_deg * kPi / 180 * 0.5 * (1 - std::cos(phase));
    const double azimuth = options.start_deg * kPi / 180 + sweep;
    const Eigen::Vector3d position =
        options.radius * Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                         std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    path.push_back(WithPose(reference, LookAtPose(position, Eigen::Vector3d::Zero())));
  }
  return path;
}

std::vector<PinholeCamera> SpiralPath(const std::vector<PinholeCamera>& cameras, const PinholeCamera& reference,
                                      double focus_distance, const CameraPathOptions& options) {
  CheckFrames(options);
  if (cameras.empty()) throw std::invalid_argument("a spiral needs the capture's cameras");
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), right = Eigen::Vector3d::Zero(), up = Eigen::Vector3d::Zero(),
                  back = Eigen::Vector3d::Zero();
  for (const PinholeCamera& camera : cameras) {
    centre += camera.world_from_cam.block<3, 1>(0, 3);
    right += camera.world_from_cam.block<3, 1>(0, 0);
    up += camera.world_from_cam.block<3, 1>(0, 1);
    back += camera.world_from_cam.block<3, 1>(0, 2);
  }
  centre /= cameras.size();
  back.normalize();
  right = (right - right.dot(back) * back).normalized();
  up = back.cross(right);
  Eigen::Vector3d spread = Eigen::Vector3d::Zero();
  for (const PinholeCamera& camera : cameras) {
    const Eigen::Vector3d d = camera.world_from_cam.block<3, 1>(0, 3) - centre;
    spread += Eigen::Vector3d(d.dot(right), d.dot(up), d.dot(back)).cwiseAbs2();
  }
  spread = (spread / cameras.size()).cwiseSqrt() * options.radius;
  const Eigen::Vector3d focus = centre - focus_distance * back;
  std::vector<PinholeCamera> path;
  for (int i = 0; i < options.frames; ++i) {
    const double angle = 4 * kPi * i / options.frames;
    const Eigen::Vector3d position = centre + spread.x() * std::cos(angle) * right + spread.y() * std::sin(angle) * up +
                                     spread.z() * std::sin(0.5 * angle) * back;
    path.push_back(WithPose(reference, LookAtPose(position, focus)));
  }
  return path;
}

std::vector<size_t> FirstOfEqualCameras(const std::vector<PinholeCamera>& cameras) {
  using Key = std::array<double, 22>;
  std::map<Key, size_t> first;
  std::vector<size_t> result;
  for (const PinholeCamera& camera : cameras) {
    Key key = {double(camera.width), double(camera.height), camera.fx, camera.fy, camera.cx, camera.cy};
    std::copy_n(camera.world_from_cam.data(), 16, key.begin() + 6);
    result.push_back(first.emplace(key, result.size()).first->second);
  }
  return result;
}

void CapturedArc(const std::vector<PinholeCamera>& cameras, double max_gap_deg, double* start_deg, double* sweep_deg) {
  std::vector<double> azimuths;
  for (const PinholeCamera& camera : cameras) {
    const Eigen::Vector3d position = camera.world_from_cam.block<3, 1>(0, 3);
    azimuths.push_back(std::fmod(std::atan2(position.y(), position.x()) * 180 / kPi + 360, 360));
  }
  std::sort(azimuths.begin(), azimuths.end());
  double widest = 0, after = 0;
  for (size_t i = 0; i < azimuths.size(); ++i) {
    const double next = i + 1 < azimuths.size() ? azimuths[i + 1] : azimuths.front() + 360;
    if (next - azimuths[i] > widest) {
      widest = next - azimuths[i];
      after = std::fmod(next, 360);
    }
  }
  *start_deg = widest > max_gap_deg ? after : 0;
  *sweep_deg = widest > max_gap_deg ? 360 - widest : 360;
}

void MeanCameraPlacement(const std::vector<PinholeCamera>& cameras, double* radius, double* elevation_deg) {
  double distance = 0, elevation = 0;
  for (const PinholeCamera& camera : cameras) {
    const Eigen::Vector3d position = camera.world_from_cam.block<3, 1>(0, 3);
    distance += position.norm();
    elevation += std::atan2(position.z(), position.head<2>().norm());
  }
  const double n = std::max<size_t>(cameras.size(), 1);
  *radius = distance / n;
  *elevation_deg = elevation / n * 180 / kPi;
}

}  // namespace p2n
