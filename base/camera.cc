#include "base/camera.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace p2n {

Eigen::Matrix3d OpenGlFromOpenCvCamera() { return Eigen::Vector3d(1, -1, -1).asDiagonal(); }
Eigen::Matrix3d OpenCvFromOpenGlCamera() { return Eigen::Vector3d(1, -1, -1).asDiagonal(); }

Eigen::Matrix4d WorldFromOpenGlCamera(const Eigen::Quaterniond& cam_from_world_rotation,
                                      const Eigen::Vector3d& cam_from_world_translation) {
  const Eigen::Matrix3d world_from_cv = cam_from_world_rotation.normalized().toRotationMatrix().transpose();
  Eigen::Matrix4d world_from_gl = Eigen::Matrix4d::Identity();
  world_from_gl.topLeftCorner<3, 3>() = world_from_cv * OpenCvFromOpenGlCamera();
  world_from_gl.topRightCorner<3, 1>() = -world_from_cv * cam_from_world_translation;
  return world_from_gl;
}

void OpenCvCamFromWorld(const Eigen::Matrix4d& world_from_gl_cam, Eigen::Quaterniond* cam_from_world_rotation,
                        Eigen::Vector3d* cam_from_world_translation) {
  const Eigen::Matrix3d world_from_cv = world_from_gl_cam.topLeftCorner<3, 3>() * OpenGlFromOpenCvCamera();
  const Eigen::Matrix3d cv_from_world = world_from_cv.transpose();
  *cam_from_world_rotation = Eigen::Quaterniond(cv_from_world).normalized();
  *cam_from_world_translation = -cv_from_world * world_from_gl_cam.topRightCorner<3, 1>();
}

PinholeCamera ScaledCamera(const PinholeCamera& camera, int width) {
  if (width == camera.width) return camera;
  const double s = double(width) / camera.width;
  PinholeCamera scaled = camera;
  scaled.width = width;
  scaled.height = std::max(1, static_cast<int>(std::lround(camera.height * s)));
  scaled.fx *= s;
  scaled.fy *= s;
  scaled.cx *= s;
  scaled.cy *= s;
  return scaled;
}

PinholeCamera ResizedCamera(const PinholeCamera& camera, int width, int height) {
  const double sx = double(width) / camera.width, sy = double(height) / camera.height;
  PinholeCamera resized = camera;
  resized.width = width;
  resized.height = height;
  resized.fx *= sx;
  resized.cx *= sx;
  resized.fy *= sy;
  resized.cy *= sy;
  return resized;
}

Eigen::Matrix4d LookAtPose(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  const Eigen::Vector3d forward = (target - position).normalized();
  Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ());
  if (right.norm() < 1e-9) right = forward.cross(Eigen::Vector3d::UnitY());
  right.normalize();
  const Eigen::Vector3d up = right.cross(forward);
  Eigen::Matrix4d world_from_cam = Eigen::Matrix4d::Identity();
  world_from_cam.block<3, 1>(0, 0) = right;
  world_from_cam.block<3, 1>(0, 1) = up;
  world_from_cam.block<3, 1>(0, 2) = -forward;  // OpenGL cameras look down -z
  world_from_cam.block<3, 1>(0, 3) = position;
  return world_from_cam;
}

Eigen::Vector2d Project(const PinholeCamera& camera, const Eigen::Vector3d& point_in_world, double* depth) {
  const Eigen::Matrix3d rotation = camera.world_from_cam.topLeftCorner<3, 3>();
  const Eigen::Vector3d in_gl = rotation.transpose() * (point_in_world - camera.world_from_cam.topRightCorner<3, 1>());
  const double z = -in_gl.z();  // distance in front of the camera
  if (depth != nullptr) *depth = z;
  return {camera.cx + camera.fx * in_gl.x() / z, camera.cy - camera.fy * in_gl.y() / z};
}

std::vector<size_t> SpreadCameras(const std::vector<PinholeCamera>& cameras, size_t count) {
  std::vector<size_t> chosen;
  if (cameras.size() <= count) {
    for (size_t i = 0; i < cameras.size(); ++i) chosen.push_back(i);
    return chosen;
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const PinholeCamera& camera : cameras) mean += camera.world_from_cam.topRightCorner<3, 1>();
  mean /= double(cameras.size());
  double spread = 0;
  for (const PinholeCamera& camera : cameras)
    spread += (camera.world_from_cam.topRightCorner<3, 1>() - mean).squaredNorm();
  spread = std::sqrt(spread / double(cameras.size()));
  // Each camera as a point: its centre in units of the spread, then its viewing direction (OpenGL looks down -z).
  std::vector<Eigen::Matrix<double, 6, 1>> keys(cameras.size());
  for (size_t i = 0; i < cameras.size(); ++i) {
    const Eigen::Vector3d centre = cameras[i].world_from_cam.topRightCorner<3, 1>() - mean;
    keys[i] << (spread > 0 ? centre / spread : centre), -cameras[i].world_from_cam.block<3, 1>(0, 2).normalized();
  }
  std::vector<double> distance(cameras.size(), std::numeric_limits<double>::infinity());
  size_t next = 0;
  while (chosen.size() < count) {
    chosen.push_back(next);
    for (size_t i = 0; i < keys.size(); ++i) distance[i] = std::min(distance[i], (keys[i] - keys[next]).squaredNorm());
    next = size_t(std::max_element(distance.begin(), distance.end()) - distance.begin());
    if (distance[next] == 0) break;  // the others stand and look where a chosen one does
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

}  // namespace p2n
