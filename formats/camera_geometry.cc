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

PrincipalFrame PrincipalAxes(const std::vector<Eigen::Vector3d>& points) {
  PrincipalFrame frame;
  if (points.empty()) return frame;
  for (const Eigen::Vector3d& p : points) frame.mean += p;
  frame.mean /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) scatter += (p - frame.mean) * (p - frame.mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
  frame.axes = solver.eigenvectors();
  frame.variances = solver.eigenvalues();
  return frame;
}

bool OutsideSpan(const std::vector<Eigen::Vector3d>& centres, const Eigen::Vector3d& point) {
  if (centres.size() < 2) return false;
  const PrincipalFrame frame = PrincipalAxes(centres);
  const Eigen::Vector3d& mean = frame.mean;
  Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY), high = -low;
  for (const Eigen::Vector3d& c : centres) {
    const Eigen::Vector3d along = frame.axes.transpose() * (c - mean);
    low = low.cwiseMin(along);
    high = high.cwiseMax(along);
  }
  const Eigen::Vector3d extent = high - low;
  const double largest = extent.maxCoeff();
  if (!(largest > 0)) return (point - mean).norm() > 0;
  const Eigen::Vector3d along = frame.axes.transpose() * (point - mean);
  Eigen::Index principal = 0;
  extent.maxCoeff(&principal);
  for (int axis = 0; axis < 3; ++axis) {
    const double margin = axis == principal ? 0.02 * largest : 0.1 * largest;
    if (along[axis] < low[axis] - margin || along[axis] > high[axis] + margin) return true;
  }
  return false;
}

}  // namespace p2n
