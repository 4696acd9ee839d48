#pragma once
// Rays from pinhole cameras (OpenGL axes, pixel (i, j)'s centre at (i + 0.5, j + 0.5)), and their intersection
// with an axis-aligned box: the near and far distances a ray spends inside the scene's cube.

#include <Eigen/Core>

#include <cstdint>
#include <optional>

#include "base/camera.h"

namespace p2n {

struct Ray {
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;  // unit length
};

// The ray through image position (u, v) in pixels (u = i + 0.5 is the centre of column i).
Ray CameraRay(const PinholeCamera& camera, double u, double v);

// The distances [near, far] (near >= 0) along `ray` inside the box [low, high]; nullopt when the ray misses it,
// only touches it, or the box lies behind the origin. Rays parallel to an axis and far-away origins are handled
// without dividing by zero or losing the hit.
std::optional<std::pair<double, double>> IntersectBox(const Ray& ray, const Eigen::Vector3d& low,
                                                      const Eigen::Vector3d& high);

}  // namespace p2n
