// Rays from cameras and their intersection with the scene's box; the spherical-harmonics direction encoding.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "examples/synthetic_scene.h"
#include "nerf/rays.h"
#include "nerf/spherical_harmonics.h"

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

// Cameras on a level circle of radius 3 at the given azimuths (degrees), looking at `target`.
std::vector<PinholeCamera> CirclingCameras(const std::vector<double>& azimuths, const Eigen::Vector3d& target) {
  std::vector<PinholeCamera> cameras;
  for (double azimuth : azimuths) {
    const double a = azimuth * M_PI / 180;
    cameras.push_back(LookAtCamera({3 * std::cos(a), 3 * std::sin(a), 0}, target, 64, 48, 60));
  }
  return cameras;
}

// The azimuth (degrees in [0, 360)) a camera stands at, and where it looks.
double StandingAzimuth(const PinholeCamera& camera) {
  const Eigen::Vector3d centre = camera.world_from_cam.topRightCorner<3, 1>();
  return std::fmod(std::atan2(centre.y(), centre.x()) * 180 / M_PI + 360, 360);
}
double LookingAzimuth(const PinholeCamera& camera) {
  const Eigen::Vector3d forward = -camera.world_from_cam.block<3, 1>(0, 2);
  return std::fmod(std::atan2(forward.y(), forward.x()) * 180 / M_PI + 360, 360);
}
double AngleApart(double a, double b) { return std::min(std::abs(a - b), 360 - std::abs(a - b)); }

TEST_CASE("spread cameras: a few of many, around an orbit, in a cluster's outskirts, by where they look", "[rays]") {
  std::vector<double> degrees;
  for (int i = 0; i < 360; ++i) degrees.push_back(i);
  const std::vector<PinholeCamera> orbit = CirclingCameras(degrees, {0, 0, 0});
  CHECK(SpreadCameras(orbit, 400).size() == 360);
  CHECK(SpreadCameras(orbit, 0).empty());

  // 8 of an orbit of 360: every camera within 45 degrees of a chosen one (farthest-point sampling is within twice
  // the best covering, 22.5), the chosen ones at least that far apart, in ascending order.
  const std::vector<size_t> eight = SpreadCameras(orbit, 8);
  REQUIRE(eight.size() == 8);
  CHECK(std::is_sorted(eight.begin(), eight.end()));
  double covering = 0, separation = 360;
  for (const PinholeCamera& camera : orbit) {
    double nearest = 360;
    for (size_t c : eight) nearest = std::min(nearest, AngleApart(StandingAzimuth(camera), StandingAzimuth(orbit[c])));
    covering = std::max(covering, nearest);
  }
  for (size_t a : eight) {
    for (size_t b : eight) {
      if (a != b) separation = std::min(separation, AngleApart(StandingAzimuth(orbit[a]), StandingAzimuth(orbit[b])));
    }
  }
  CHECK(covering <= 45 + 1e-9);
  CHECK(separation >= 22.5);

  // 300 cameras within 3 degrees of each other and 5 elsewhere: 6 chosen take the 5 and one of the 300.
  std::vector<double> clustered;
  for (int i = 0; i < 300; ++i) clustered.push_back(i * 0.01);
  for (double azimuth : {60, 130, 190, 250, 310}) clustered.push_back(azimuth);
  const std::vector<size_t> six = SpreadCameras(CirclingCameras(clustered, {0, 0, 0}), 6);
  REQUIRE(six.size() == 6);
  CHECK(six[0] < 300);
  for (size_t k = 1; k < 6; ++k) CHECK(six[k] == 299 + k);

  // Standing in one place, the chosen ones look around: 4 of 72 looking every 5 degrees, at least 90 apart.
  std::vector<PinholeCamera> panorama;
  for (int i = 0; i < 72; ++i) {
    const double a = i * 5 * M_PI / 180;
    panorama.push_back(LookAtCamera({0, 0, 0}, {std::cos(a), std::sin(a), 0}, 64, 48, 60));
  }
  const std::vector<size_t> four = SpreadCameras(panorama, 4);
  REQUIRE(four.size() == 4);
  for (size_t k = 1; k < 4; ++k)
    CHECK(AngleApart(LookingAzimuth(panorama[four[k]]), LookingAzimuth(panorama[four[k - 1]])) >= 90 - 1e-9);

  // Cameras that coincide give one.
  CHECK(SpreadCameras(std::vector<PinholeCamera>(10, orbit[7]), 3) == std::vector<size_t>{0});
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
