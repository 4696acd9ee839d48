#include "nerf/camera_refinement.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <cmath>

namespace p2n {
namespace {

Eigen::Vector3d RotationVector(const float* correction) {
  return Eigen::Vector3d(correction[0], correction[1], correction[2]);
}

Eigen::Matrix3d Rotation(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The left Jacobian of SO(3): Rotation(w + e) = Rotation(LeftJacobian(w) e) Rotation(w) to first order in e.
Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  const Eigen::Matrix3d k = Skew(w);
  if (angle < 1e-4) return Eigen::Matrix3d::Identity() + 0.5 * k + k * k / 6;
  return Eigen::Matrix3d::Identity() + (1 - std::cos(angle)) / (angle * angle) * k +
         (angle - std::sin(angle)) / (angle * angle * angle) * k * k;
}

}  // namespace

Ray CorrectRay(const float* correction, const Ray& ray) {
  return {ray.origin + Eigen::Vector3d(correction[3], correction[4], correction[5]),
          Rotation(RotationVector(correction)) * ray.direction};
}

void CorrectRayBackward(const float* correction, const Eigen::Vector3d& corrected_direction,
                        const Eigen::Vector3d& d_origin, const Eigen::Vector3d& d_direction, float* d_correction) {
  // direction' = R(w) direction: d(direction')/dw = -[direction']x J(w).
  const Eigen::Vector3d d_rotation =
      LeftJacobian(RotationVector(correction)).transpose() * corrected_direction.cross(d_direction);
  for (int k = 0; k < 3; ++k) {
    d_correction[k] += static_cast<float>(d_rotation[k]);
    d_correction[3 + k] += static_cast<float>(d_origin[k]);
  }
}

PinholeCamera CorrectedCamera(const PinholeCamera& camera, const float* correction) {
  PinholeCamera out = camera;
  out.world_from_cam.block<3, 3>(0, 0) = Rotation(RotationVector(correction)) * camera.world_from_cam.block<3, 3>(0, 0);
  out.world_from_cam.block<3, 1>(0, 3) += Eigen::Vector3d(correction[3], correction[4], correction[5]);
  return out;
}

void RemoveCommonMotion(const std::vector<Eigen::Vector3d>& centres, std::vector<float>* corrections) {
  // Unknowns x = [w (3), s, u (3)]: view i's rotation is w and its shift is w x c_i + s c_i + u.
  double radius = 0;
  for (const Eigen::Vector3d& c : centres) radius += c.squaredNorm();
  radius = std::sqrt(radius / std::max<size_t>(centres.size(), 1)) + 1e-9;
  Eigen::Matrix<double, 7, 7> normal = 1e-12 * Eigen::Matrix<double, 7, 7>::Identity();
  Eigen::Matrix<double, 7, 1> rhs = Eigen::Matrix<double, 7, 1>::Zero();
  std::vector<Eigen::Matrix<double, 6, 7>> rows(centres.size());
  for (size_t i = 0; i < centres.size(); ++i) {
    Eigen::Matrix<double, 6, 7>& a = rows[i];
    a.setZero();
    a.block<3, 3>(0, 0) = radius * Eigen::Matrix3d::Identity();
    a.block<3, 3>(3, 0) = -Skew(centres[i]);
    a.block<3, 1>(3, 3) = centres[i];
    a.block<3, 3>(3, 4) = Eigen::Matrix3d::Identity();
    Eigen::Matrix<double, 6, 1> b;
    const float* c = &(*corrections)[i * kPoseParams];
    b << radius * RotationVector(c), Eigen::Vector3d(c[3], c[4], c[5]);
    normal += a.transpose() * a;
    rhs += a.transpose() * b;
  }
  const Eigen::Matrix<double, 7, 1> x = normal.ldlt().solve(rhs);
  for (size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Matrix<double, 6, 1> common = rows[i] * x;
    float* c = &(*corrections)[i * kPoseParams];
    for (int k = 0; k < 3; ++k) {
      c[k] -= static_cast<float>(common[k] / radius);
      c[3 + k] -= static_cast<float>(common[3 + k]);
    }
  }
}

double CorrectionDegrees(const float* correction) { return RotationVector(correction).norm() * 180 / M_PI; }

double CorrectionShift(const float* correction) {
  return Eigen::Vector3d(correction[3], correction[4], correction[5]).norm();
}

}  // namespace p2n
