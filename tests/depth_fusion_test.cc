// Depth maps fused into a surface, on a sphere seen from around: the fused surface lies on the sphere within a
// fraction of a cell, is closed and wound outwards, and a floater that one view alone sees is carved away; on a
// ground seen from above: the ground alone, open at the cube's edges, not a slab down to the cube's floor.

#include <catch2/catch.hpp>

#include <cmath>

#include "mesh/depth_fusion.h"
#include "mesh/mesh.h"
#include "nerf/rays.h"
#include "tests/sphere_field.h"

namespace p2n::testing {
namespace {

struct Rendered {
  PinholeCamera camera;
  FloatImage depth, opacity;
};

// The sphere of radius kRadius at the origin (and, when `floater`, a ball of radius 0.08 at (0, 0, 0.85)), or
// with `ground` the plane z = -0.3 alone, seen by a camera 2.5 units off, looking at the centre.
Rendered RenderSphere(const Eigen::Vector3d& eye, bool floater, bool ground = false) {
  Rendered out;
  PinholeCamera& camera = out.camera;
  camera.width = camera.height = 96;
  camera.fx = camera.fy = 110;
  camera.cx = camera.cy = 48;
  camera.world_from_cam = LookAtPose(eye, Eigen::Vector3d::Zero());
  out.depth = {96, 96, 1, std::vector<float>(96 * 96, 0)};
  out.opacity = out.depth;
  const auto hit = [](const Ray& ray, const Eigen::Vector3d& centre, double radius) {
    const Eigen::Vector3d o = ray.origin - centre;
    const double b = o.dot(ray.direction), disc = b * b - (o.squaredNorm() - radius * radius);
    return disc > 0 ? -b - std::sqrt(disc) : INFINITY;
  };
  for (int y = 0; y < 96; ++y) {
    for (int x = 0; x < 96; ++x) {
      const Ray ray = CameraRay(camera, x + 0.5, y + 0.5);
      double t = ground ? (ray.direction.z() < 0 ? (-0.3 - ray.origin.z()) / ray.direction.z() : INFINITY)
                        : hit(ray, Eigen::Vector3d::Zero(), kRadius);
      if (floater) t = std::min(t, hit(ray, Eigen::Vector3d(0, 0, 0.85), 0.08));
      if (!std::isfinite(t)) continue;
      out.depth.pixels[y * 96 + x] = static_cast<float>(t);
      out.opacity.pixels[y * 96 + x] = 1;
    }
  }
  return out;
}

}  // namespace

TEST_CASE("depth fusion: depths of a sphere from around fuse to the sphere, a floater one view saw carved away",
          "[mesh]") {
  std::vector<Rendered> views;
  for (int i = 0; i < 12; ++i) {
    const double azimuth = 2 * M_PI * i / 12, elevation = (i % 3 - 1) * 0.6;
    const Eigen::Vector3d eye = 2.5 * Eigen::Vector3d(std::cos(azimuth) * std::cos(elevation),
                                                      std::sin(azimuth) * std::cos(elevation), std::sin(elevation));
    views.push_back(RenderSphere(eye, i == 0));  // the floater in the first view only
  }
  std::vector<DepthMap> maps;
  for (const Rendered& view : views) maps.push_back({view.camera, &view.depth, &view.opacity});
  MeshOptions lattice;
  lattice.resolution = 64;
  const Mesh mesh = ExtractFusedSurface(SphereModel(), lattice, FuseDepths(maps, lattice, {}));

  REQUIRE(mesh.triangles.size() > 1000);
  CHECK(CountEdges(mesh).watertight());
  const float cell = 2.0f / lattice.resolution;
  size_t off = 0;
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const Eigen::Vector3f& p = mesh.positions[v];
    off += std::abs(p.norm() - kRadius) > 0.5f * cell;
    CHECK(mesh.normals[v].dot(p.normalized()) > 0.9f);
    CHECK((p - Eigen::Vector3f(0, 0, 0.85f)).norm() > 0.15f);  // nothing of the floater
  }
  CHECK(off < mesh.positions.size() / 100);
  CHECK(SignedVolume(mesh.positions, mesh.triangles) == Approx(4.0 / 3.0 * M_PI * std::pow(kRadius, 3)).epsilon(0.05));
}

TEST_CASE("depth fusion: a ground seen from above is a sheet, open at the cube's edges", "[mesh]") {
  std::vector<Rendered> views;
  for (int i = 0; i < 8; ++i) {
    const double azimuth = 2 * M_PI * i / 8;
    views.push_back(
        RenderSphere(2.5 * Eigen::Vector3d(0.6 * std::cos(azimuth), 0.6 * std::sin(azimuth), 0.8), false, true));
  }
  std::vector<DepthMap> maps;
  for (const Rendered& view : views) maps.push_back({view.camera, &view.depth, &view.opacity});
  MeshOptions lattice;
  lattice.resolution = 48;
  lattice.half_size = 0.5;
  const Mesh mesh = ExtractFusedSurface(SphereModel(), lattice, FuseDepths(maps, lattice, {}));
  REQUIRE(mesh.triangles.size() > 500);
  const float cell = 1.0f / lattice.resolution;
  // Within a cell: the depth maps' pixels are about a cell wide there.
  for (const Eigen::Vector3f& p : mesh.positions) CHECK(std::abs(p.z() + 0.3f) < cell);
  double area = 0;
  for (const auto& t : mesh.triangles) {
    area +=
        0.5 * (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]).norm();
  }
  CHECK(area == Approx(1.0).epsilon(0.1));  // the cube's cross-section, its border cells left open
  CHECK(CountEdges(mesh).border > 0);
}

}  // namespace p2n::testing
