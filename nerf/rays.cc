#include "nerf/rays.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace p2n {

Ray CameraRay(const PinholeCamera& camera, double u, double v) {
  const Eigen::Vector3d in_camera((u - camera.cx) / camera.fx, -(v - camera.cy) / camera.fy, -1.0);
  Ray ray;
  ray.origin = camera.world_from_cam.topRightCorner<3, 1>();
  ray.direction = (camera.world_from_cam.topLeftCorner<3, 3>() * in_camera).normalized();
  return ray;
}

std::optional<std::pair<double, double>> IntersectBox(const Ray& ray, const Eigen::Vector3d& low,
                                                      const Eigen::Vector3d& high) {
  double near = 0, far = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    const double o = ray.origin[axis], d = ray.direction[axis];
    if (d == 0) {
      // Parallel to this pair of faces: strictly inside the slab, or never (a ray in a face only touches).
      if (!(o > low[axis] && o < high[axis])) return std::nullopt;
      continue;
    }
    // 1/d is +-inf only for d == 0, handled above; tiny d gives huge but ordered distances.
    double t0 = (low[axis] - o) / d, t1 = (high[axis] - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    near = std::max(near, t0);
    far = std::min(far, t1);
    if (near >= far) return std::nullopt;
  }
  return std::make_pair(near, far);
}

}  // namespace p2n
