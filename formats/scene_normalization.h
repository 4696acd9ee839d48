#pragma once
// Normalising a reconstruction for the NeRF: centre, up direction and scale, so that the region of interest
// fits the unit cube [-1, 1]^3. Every division has a guard; degenerate inputs fall back in documented ways or
// fail with a UserError, never produce NaN.

#include <Eigen/Core>

#include <string>
#include <vector>

namespace p2n {

struct Normalization {
  Eigen::Matrix4d normalized_from_world = Eigen::Matrix4d::Identity();  // a similarity: scale * rotation, shift
  double scale = 1;
  std::string centre_from;  // "focus point", "sparse points", "cameras"
  std::string up_from;      // "camera up vectors", "camera plane", "none"
  std::vector<std::string> warnings;
};

// `centres`, `ups` and `axes`: each camera's centre, up direction and viewing direction in world coordinates;
// `points`: the sparse points. Fallbacks: centre at the focus point of the optical axes, else the median of the
// points, else the centroid of the cameras; up from the mean camera up vector, else the normal of the
// cameras' plane, else none; scale from the 95th percentile of the points' extent, else the cameras'.
// UserError when there is no camera, or every camera and point sits at one place.
Normalization NormalizeScene(const std::vector<Eigen::Vector3d>& centres, const std::vector<Eigen::Vector3d>& ups,
                             const std::vector<Eigen::Vector3d>& axes, const std::vector<Eigen::Vector3d>& points);

}  // namespace p2n
