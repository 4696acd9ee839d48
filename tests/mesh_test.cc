// Marching cubes on a field with a known surface: a sphere whose density crosses the threshold exactly at
// radius 0.6, coloured by the direction it is seen from. The mesh must be closed, lie on the sphere within a
// fraction of a cell, point its normals and its triangles' winding outwards, and carry the colour seen along
// minus the normal.

#include <catch2/catch.hpp>

#include <cmath>

#include "examples/synthetic_scene.h"
#include "mesh/mesh.h"
#include "nerf/rays.h"
#include "nerf/renderer.h"
#include "tests/sphere_field.h"

namespace p2n::testing {

TEST_CASE("mesh: a sphere's surface is closed, on the sphere, oriented outwards and coloured from outside", "[mesh]") {
  const NerfModel model = SphereModel();
  MeshOptions options;
  options.resolution = 48;
  options.density_threshold = kThreshold;
  size_t slices = 0;
  const Mesh mesh = ExtractMesh(model, options, [&](size_t n) { slices += n; });
  CHECK(slices == 48);
  REQUIRE(mesh.triangles.size() > 1000);
  CHECK(CountEdges(mesh).watertight());
  const float cell = 2.0f / options.resolution;
  CHECK(SignedVolume(mesh.positions, mesh.triangles) ==
        Approx(4.0 / 3.0 * M_PI * std::pow(kRadius, 3)).epsilon(0.03));  // > 0: wound outwards
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    const Eigen::Vector3f& p = mesh.positions[v];
    REQUIRE(p.allFinite());
    CHECK(std::abs(p.norm() - kRadius) < 0.1f * cell);
    CHECK(mesh.normals[v].dot(p.normalized()) > 0.99f);
    // Seen along -normal, the colour is (1 + normal) / 2.
    for (int c = 0; c < 3; ++c) CHECK(std::abs(mesh.colours[v][c] - 127.5f * (1 + mesh.normals[v][c])) <= 2.0f);
  }
}

TEST_CASE("mesh: a surface cut by the box is closed by the box's faces, an empty field gives no mesh", "[mesh]") {
  NerfModel model = SphereModel(1.2f);  // the faces' centres are inside, the corners outside
  MeshOptions options;
  options.resolution = 24;
  options.density_threshold = kThreshold;
  const Mesh cut = ExtractMesh(model, options);
  CHECK(CountEdges(cut).watertight());
  for (const Eigen::Vector3f& p : cut.positions) CHECK(p.cwiseAbs().maxCoeff() <= 1.0f);

  options.density_threshold = 1e9f;
  CHECK(ExtractMesh(model, options).triangles.empty());
  CHECK_FALSE(CountEdges(Mesh{}).watertight());
  options.resolution = 4;
  CHECK_THROWS_AS(ExtractMesh(model, options), std::invalid_argument);
}

TEST_CASE("mesh: a smaller cube off the centre meshes only its part of the surface, at its own cell size", "[mesh]") {
  const NerfModel model = SphereModel();
  MeshOptions options;
  options.resolution = 32;
  options.density_threshold = kThreshold;
  options.centre = Eigen::Vector3d(0.4, 0, 0);
  options.half_size = 0.4;  // x in [0, 0.8], y and z in [-0.4, 0.4]: cuts the sphere of radius 0.6
  const Mesh mesh = ExtractMesh(model, options);
  REQUIRE(mesh.triangles.size() > 500);
  CHECK(CountEdges(mesh).watertight());  // closed by the cube's faces
  const float cell = 2.0f * 0.4f / options.resolution;
  size_t on_sphere = 0;
  for (const Eigen::Vector3f& p : mesh.positions) {
    const Eigen::Vector3f local = p - Eigen::Vector3f(0.4f, 0, 0);
    REQUIRE(local.cwiseAbs().maxCoeff() <= 0.4f + 1e-6f);
    // Away from the cube's faces (the caps that close the mesh reach half a cell in), on the sphere.
    if (local.cwiseAbs().maxCoeff() < 0.4f - cell) {
      CHECK(std::abs(p.norm() - kRadius) < 0.1f * cell);
      ++on_sphere;
    }
  }
  CHECK(on_sphere > 100);
  options.half_size = 0;
  CHECK_THROWS_WITH(ExtractMesh(model, options), Catch::Contains("half_size"));
}

TEST_CASE(
    "mesh: a cube fitted to points spans their bulk, inside the scene box (or beyond it where asked), outliers "
    "ignored",
    "[mesh]") {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 1000; ++i) {  // evenly in x in [0.1, 0.5], y in [-0.2, 0.2], z in [0, 0.2]
    const double u = (i % 10 + 0.5) / 10, v = (i / 10 % 10 + 0.5) / 10, w = (i / 100 + 0.5) / 10;
    points.emplace_back(0.1 + 0.4 * u, -0.2 + 0.4 * v, 0.2 * w);
  }
  for (int i = 0; i < 40; ++i) points.emplace_back(5.0, -3.0, 0.9);  // 4%: floaters and background
  MeshOptions options;
  FitCube(points, &options);
  // The 5th to 95th percentile along x is about [0.12, 0.48]; half of it widened by 1.2 about 0.22.
  CHECK(options.half_size == Approx(0.5 * 1.2 * 0.36).margin(0.02));
  CHECK(options.centre.x() == Approx(0.3).margin(0.02));
  CHECK(options.centre.y() == Approx(0.0).margin(0.02));
  CHECK(options.centre.z() == Approx(0.1).margin(0.02));

  // Near the box's face, the cube moves inwards; too few points leave it alone.
  for (Eigen::Vector3d& p : points) p.x() += 0.6;  // the bulk reaches past x = 1
  MeshOptions moved;
  FitCube(points, &moved);
  CHECK(moved.centre.x() + moved.half_size <= 1.0 + 1e-12);
  CHECK(moved.half_size == Approx(options.half_size).margin(1e-9));
  MeshOptions few;
  FitCube(std::vector<Eigen::Vector3d>(points.begin(), points.begin() + 50), &few);
  CHECK((few.half_size == 1.0 && few.centre == Eigen::Vector3d::Zero()));

  // All of the bulk beyond the box: no cube inside it; one around the bulk where the field covers that space.
  for (Eigen::Vector3d& p : points) p += Eigen::Vector3d(0, 0, 20);
  MeshOptions outside;
  FitCube(points, &outside);
  CHECK((outside.half_size == 1.0 && outside.centre == Eigen::Vector3d::Zero()));
  FitCube(points, &outside, true);
  CHECK(outside.half_size == Approx(options.half_size).margin(0.02));
  CHECK(outside.centre.x() == Approx(0.9).margin(0.02));
  CHECK(outside.centre.z() == Approx(20.1).margin(0.02));
}

TEST_CASE("mesh: the threshold chosen from the field puts the surface where the views see it", "[mesh]") {
  // The sphere's density ramps up from 0 at radius 0.6625 by 400 per unit inwards: no hard surface, so the
  // rendered depth lies some way inside; the mesh must follow it, not a fixed density.
  NerfModel model = SphereModel();
  model.march_step = 2 * std::sqrt(3.0) / 512;
  std::vector<Eigen::Vector3d> surface;
  for (const Eigen::Vector3d& position :
       {Eigen::Vector3d(3, 0, 0.5), Eigen::Vector3d(-2, 2, 1), Eigen::Vector3d(0, -3, -1)}) {
    const PinholeCamera camera = LookAtCamera(position, Eigen::Vector3d::Zero(), 40, 40, 40);
    const RenderedView view = RenderView(model, camera, -1, -1, RenderOptions{});
    for (int y = 0; y < camera.height; ++y) {
      for (int x = 0; x < camera.width; ++x) {
        const size_t i = size_t(y) * camera.width + x;
        if (view.opacity.pixels[i] < 0.95f) continue;
        const Ray ray = CameraRay(camera, x + 0.5, y + 0.5);
        surface.push_back(ray.origin + view.depth.pixels[i] * ray.direction);
      }
    }
  }
  REQUIRE(surface.size() > 300);
  const float threshold = SurfaceThreshold(model, surface);
  CHECK(threshold > 5);
  CHECK(threshold < 40);
  MeshOptions options;
  options.resolution = 48;
  options.density_threshold = threshold;
  const Mesh mesh = ExtractMesh(model, options);
  REQUIRE(!mesh.positions.empty());
  double mesh_radius = 0, depth_radius = 0;
  for (const Eigen::Vector3f& p : mesh.positions) mesh_radius += p.norm() / mesh.positions.size();
  for (const Eigen::Vector3d& p : surface) depth_radius += p.norm() / surface.size();
  CHECK(std::abs(mesh_radius - depth_radius) < 2.0 / options.resolution);  // within a cell
  CHECK(SurfaceThreshold(model, {}) == 0);
}

TEST_CASE("mesh: cells the occupancy grid marks empty are not evaluated", "[mesh]") {
  NerfModel model = SphereModel();
  model.occupancy = OccupancyGrid(16);
  model.occupancy.Update([](const Eigen::Matrix3Xf& p) { return Eigen::VectorXf::Zero(p.cols()).eval(); }, 1.0f, 0.0f,
                         0);  // every cell empty
  MeshOptions options;
  options.resolution = 32;
  CHECK(ExtractMesh(model, options).triangles.empty());
}

TEST_CASE("mesh: edge counts find holes, non-manifold edges and flipped triangles", "[mesh]") {
  Mesh tetrahedron;
  tetrahedron.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tetrahedron.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  const MeshEdges closed = CountEdges(tetrahedron);
  CHECK(closed.edges == 6);
  CHECK(closed.watertight());

  Mesh flipped = tetrahedron;
  std::swap(flipped.triangles[3][1], flipped.triangles[3][2]);
  CHECK(CountEdges(flipped).misoriented == 3);
  Mesh holed = tetrahedron;
  holed.triangles.pop_back();
  CHECK(CountEdges(holed).border == 3);
  Mesh fin = tetrahedron;
  fin.positions.push_back({1, 1, 1});
  fin.triangles.push_back({0, 1, 4});  // a third triangle on edge 0-1
  CHECK(CountEdges(fin).non_manifold == 1);
  CHECK_FALSE(CountEdges(fin).watertight());
}

}  // namespace p2n::testing
