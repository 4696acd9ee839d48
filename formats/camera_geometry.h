#pragma once
// Geometry of a set of cameras that the sfm check, the poses normalisation and the held-out choice use.

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

// The centroid of `points` and their principal axes: the columns of `axes`, by increasing spread (`variances`, the
// eigenvalues of their scatter matrix, unnormalised).
struct PrincipalFrame {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector3d variances = Eigen::Vector3d::Zero();
};
PrincipalFrame PrincipalAxes(const std::vector<Eigen::Vector3d>& points);

// Whether `point` (a camera centre) lies outside the span of the other cameras' `centres`: beyond their extent along
// the principal axis they spread along most (by more than 2% of it: the ends of an arc), or along another principal
// axis by more than a tenth of that extent (off the plane they lie in; not the middle of an arc, which bulges past
// the others' chord). A view taken from there is an extrapolation of the others. False for fewer than 2 centres.
bool OutsideSpan(const std::vector<Eigen::Vector3d>& centres, const Eigen::Vector3d& point);

}  // namespace p2n
