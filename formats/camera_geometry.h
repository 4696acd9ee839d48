#pragma once
// Geometry of a set of cameras that both the sfm check and the poses normalisation use.

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace p2n {

struct FocusPoint {
  Eigen::Vector3d point;
  double median_angle_deg;  // median angle between each optical axis and the direction to the point
};

// The point closest (least squares) to every camera's optical axis: what an orbiting capture looks at.
// nullopt when the axes are (nearly) parallel, as in a forward-facing capture, or when fewer than 2 cameras.
std::optional<FocusPoint> FindFocusPoint(const std::vector<Eigen::Vector3d>& centres,
                                         const std::vector<Eigen::Vector3d>& axes);

}  // namespace p2n
