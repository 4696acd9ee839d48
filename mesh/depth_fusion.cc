#include "mesh/depth_fusion.h"

#include <tbb/parallel_for.h>

#include <cmath>

namespace p2n {
namespace {

// A view's projection: camera axes (OpenGL) from world, and its pixels.
struct Projector {
  Eigen::Matrix3d rotation;  // cam_from_world
  Eigen::Vector3d centre;
  const DepthMap* map;

  explicit Projector(const DepthMap& m) : map(&m) {
    rotation = m.camera.world_from_cam.topLeftCorner<3, 3>().transpose();
    centre = m.camera.world_from_cam.topRightCorner<3, 1>();
  }

  // The pixel `point` falls in and its distance from the centre, or false outside the image or behind.
  bool Pixel(const Eigen::Vector3d& point, size_t* pixel, double* distance) const {
    const Eigen::Vector3d offset = point - centre, in_camera = rotation * offset;
    if (in_camera.z() >= 0) return false;
    const PinholeCamera& c = map->camera;
    const double u = c.cx + c.fx * in_camera.x() / -in_camera.z(), v = c.cy - c.fy * in_camera.y() / -in_camera.z();
    if (!(u >= 0 && v >= 0 && u < c.width && v < c.height)) return false;
    *pixel = size_t(v) * c.width + size_t(u);
    *distance = offset.norm();
    return true;
  }
};

// What the views say of one point.
struct Votes {
  double distance_sum = 0;  // of the views that see a surface within the truncation, in truncations
  int near = 0, free = 0, behind = 0;

  float Value() const {
    if (free > near) return 1;  // mostly seen through: empty space
    if (near > 0) return static_cast<float>(distance_sum / near);
    return behind > 0 ? -1.0f : 1.0f;
  }
};

}  // namespace

std::vector<float> FuseDepths(const std::vector<DepthMap>& maps, const MeshOptions& lattice,
                              const FusionOptions& options) {
  const int n = lattice.resolution;
  const double truncation = options.truncation_cells * 2 * lattice.half_size / n;
  std::vector<Projector> projectors;
  for (const DepthMap& map : maps) projectors.emplace_back(map);
  std::vector<float> values(size_t(n) * n * n, 1.0f);
  tbb::parallel_for(0, n, [&](int i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector3d point = LatticePoint(lattice, i, j, k);
        Votes votes;
        for (const Projector& projector : projectors) {
          size_t pixel;
          double distance;
          if (!projector.Pixel(point, &pixel, &distance)) continue;
          if (projector.map->opacity->pixels[pixel] < options.min_opacity) {
            ++votes.free;
            continue;
          }
          const double signed_distance = projector.map->depth->pixels[pixel] - distance;
          if (signed_distance > truncation) {
            ++votes.free;
          } else if (signed_distance < -truncation) {
            ++votes.behind;
          } else {
            votes.distance_sum += signed_distance / truncation;
            ++votes.near;
          }
        }
        values[(size_t(i) * n + j) * n + k] = votes.Value();
      }
    }
  });
  return values;
}

}  // namespace p2n
