// Rays from cameras and their intersection with the scene's box; the spherical-harmonics direction encoding.

#include <catch2/catch.hpp>

#include <cmath>

#include "nerf/rays.h"
#include "nerf/spherical_harmonics.h"
#include "nerf/synthetic_scene.h"

namespace p2n::testing {

TEST_CASE("a camera ray projects back to its pixel, the principal point looks down the optical axis", "[rays]") {
  const PinholeCamera camera = LookAtCamera({3, -2, 1.5}, {0, 0, 0.4}, 320, 240, 60);
  for (const auto& [u, v] :
       {std::pair{0.5, 0.5}, std::pair{319.5, 0.5}, std::pair{160.0, 120.0}, std::pair{17.25, 203.75}}) {
    const Ray ray = CameraRay(camera, u, v);
    CHECK(ray.direction.norm() == Approx(1.0));
    double depth = 0;
    const Eigen::Vector2d pixel = Project(camera, ray.origin + 3.7 * ray.direction, &depth);
    CHECK(pixel.x() == Approx(u).margin(1e-9));
    CHECK(pixel.y() == Approx(v).margin(1e-9));
    CHECK(depth > 0);
  }
  const Ray centre = CameraRay(camera, camera.cx, camera.cy);
  CHECK((centre.direction + camera.world_from_cam.block<3, 1>(0, 2)).norm() < 1e-12);
}

TEST_CASE("a resized camera sees each point at the same place in the image, each axis scaled", "[rays]") {
  const PinholeCamera camera = LookAtCamera({3, -2, 1.5}, {0, 0, 0.4}, 320, 240, 60);
  const PinholeCamera resized = ResizedCamera(camera, 101, 77);  // not the aspect ratio: each axis its own scale
  CHECK(resized.width == 101);
  CHECK(resized.height == 77);
  for (const Eigen::Vector3d& point : {Eigen::Vector3d(0, 0, 0.4), Eigen::Vector3d(0.3, -0.2, 0.1)}) {
    const Eigen::Vector2d before = Project(camera, point), after = Project(resized, point);
    CHECK(after.x() == Approx(before.x() * 101 / 320));
    CHECK(after.y() == Approx(before.y() * 77 / 240));
  }
  // The image's far corner stays the far corner.
  const Ray corner = CameraRay(camera, 320, 240);
  const Eigen::Vector2d far_corner = Project(resized, corner.origin + 2 * corner.direction);
  CHECK(far_corner.x() == Approx(101));
  CHECK(far_corner.y() == Approx(77));
}

TEST_CASE("ray-box intersection: hits, misses, axis-parallel, behind, grazing and far-away rays", "[rays]") {
  const Eigen::Vector3d low(-1, -1, -1), high(1, 1, 1);
  const auto hit = [&](Eigen::Vector3d origin, Eigen::Vector3d direction) {
    return IntersectBox(Ray{origin, direction.normalized()}, low, high);
  };
  auto through = hit({-3, 0, 0}, {1, 0, 0});
  REQUIRE(through);
  CHECK(through->first == 2.0);
  CHECK(through->second == 4.0);
  auto inside = hit({0.5, 0, 0}, {0, 0, 1});
  REQUIRE(inside);
  CHECK(inside->first == 0.0);
  CHECK(inside->second == 1.0);
  CHECK_FALSE(hit({-3, 2, 0}, {1, 0, 0}));    // parallel, outside the slab
  CHECK_FALSE(hit({3, 0, 0}, {1, 0, 0}));     // the box is behind
  CHECK_FALSE(hit({-3, 0, 0}, {1, 1.5, 0}));  // passes beside it
  CHECK_FALSE(hit({-3, 1, 1}, {1, 0, 0}));    // along an edge: it only touches the box
  CHECK_FALSE(hit({-3, 1, 0}, {1, 0, 0}));    // in a face: the same
  auto diagonal = hit({-2, -2, -2}, {1, 1, 1});
  REQUIRE(diagonal);
  CHECK(diagonal->second - diagonal->first == Approx(2 * std::sqrt(3.0)));
  auto far_away = hit({1e8, 0.5, 0.5}, {-1, 0, 0});
  REQUIRE(far_away);
  CHECK(far_away->second - far_away->first == Approx(2.0).epsilon(1e-6));
  auto tiny = hit({0, 0, -5}, {1e-300, 0, 1});  // a nearly axis-parallel direction
  REQUIRE(tiny);
  CHECK(std::isfinite(tiny->first));
  CHECK(tiny->second == Approx(6.0));
}

TEST_CASE("spherical harmonics are orthonormal over the sphere", "[rays]") {
  // Fibonacci points: a near-uniform quadrature of the sphere.
  constexpr int kPoints = 40000;
  double gram[16][16] = {};
  for (int i = 0; i < kPoints; ++i) {
    const double z = 1 - (2 * i + 1.0) / kPoints;
    const double r = std::sqrt(1 - z * z), phi = i * M_PI * (3 - std::sqrt(5.0));
    double values[16];
    SphericalHarmonics(r * std::cos(phi), r * std::sin(phi), z, values);
    for (int a = 0; a < 16; ++a) {
      for (int b = 0; b < 16; ++b) gram[a][b] += values[a] * values[b] * 4 * M_PI / kPoints;
    }
  }
  for (int a = 0; a < 16; ++a) {
    for (int b = 0; b < 16; ++b) CHECK(gram[a][b] == Approx(a == b ? 1.0 : 0.0).margin(2e-3));
  }
}

}  // namespace p2n::testing
