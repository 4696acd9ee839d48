#include "formats/camera_geometry.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace p2n {

std::optional<FocusPoint> FindFocusPoint(const std::vector<Eigen::Vector3d>& centres,
                                         const std::vector<Eigen::Vector3d>& axes) {
  if (centres.size() < 2 || centres.size() != axes.size()) return std::nullopt;
  // Minimise sum |(I - d d^T)(p - c)|^2: solve sum (I - d d^T) p = sum (I - d d^T) c.
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Vector3d d = axes[i].normalized();
    const Eigen::Matrix3d projector = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += projector;
    b += projector * centres[i];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a);
  // Parallel axes leave one direction unconstrained: the smallest eigenvalue is ~0.
  if (eigen.eigenvalues()(0) < 1e-3 * eigen.eigenvalues()(2)) return std::nullopt;
  FocusPoint focus;
  focus.point = a.ldlt().solve(b);
  std::vector<double> angles;
  for (size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Vector3d to_point = focus.point - centres[i];
    const double cosine = to_point.normalized().dot(axes[i].normalized());
    angles.push_back(std::acos(std::clamp(cosine, -1.0, 1.0)) * 180 / M_PI);
  }
  std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
  focus.median_angle_deg = angles[angles.size() / 2];
  return focus;
}

}  // namespace p2n
