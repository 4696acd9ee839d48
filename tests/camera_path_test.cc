// Camera paths: orbits at the asked radius and elevation looking at the centre; spirals around the capture's
// cameras looking at their focus; the placement of a ring of cameras recovered.

#include <catch2/catch.hpp>

#include <cmath>

#include "nerf/camera_path.h"
#include "nerf/synthetic_scene.h"

namespace p2n::testing {

TEST_CASE("camera paths: an orbit circles the centre at its radius and elevation, looking at the centre", "[path]") {
  const PinholeCamera reference = LookAtCamera({3, 0, 1}, {0, 0, 0}, 80, 60, 50);
  CameraPathOptions options;
  options.frames = 12;
  options.radius = 2.5;
  options.elevation_deg = 30;
  const std::vector<PinholeCamera> path = OrbitPath(reference, options);
  REQUIRE(path.size() == 12);
  for (const PinholeCamera& camera : path) {
    CHECK(camera.width == 80);
    CHECK(camera.fx == reference.fx);
    const Eigen::Vector3d position = camera.world_from_cam.block<3, 1>(0, 3);
    CHECK(position.norm() == Approx(2.5));
    CHECK(position.z() == Approx(2.5 * std::sin(M_PI / 6)));
    CHECK(Project(camera, Eigen::Vector3d::Zero()).isApprox(Eigen::Vector2d(camera.cx, camera.cy), 1e-9));
  }
  double radius = 0, elevation = 0;
  MeanCameraPlacement(path, &radius, &elevation);
  CHECK(radius == Approx(2.5));
  CHECK(elevation == Approx(30));
  options.frames = 0;
  CHECK_THROWS_AS(OrbitPath(reference, options), std::invalid_argument);
}

TEST_CASE("camera paths: a spiral stays near the capture and looks at its focus", "[path]") {
  std::vector<PinholeCamera> capture;
  for (int i = 0; i < 9; ++i)
    capture.push_back(LookAtCamera({0.1 * (i % 3 - 1), 0.1 * (i / 3 - 1) - 3, 0}, {0, 0, 0}, 64, 48, 60));
  CameraPathOptions options;
  options.frames = 20;
  options.radius = 1;
  const std::vector<PinholeCamera> path = SpiralPath(capture, capture[4], 3.0, options);
  REQUIRE(path.size() == 20);
  for (const PinholeCamera& camera : path) {
    const Eigen::Vector3d position = camera.world_from_cam.block<3, 1>(0, 3);
    CHECK((position - Eigen::Vector3d(0, -3, 0)).norm() < 0.3);
    CHECK(Project(camera, Eigen::Vector3d::Zero()).isApprox(Eigen::Vector2d(camera.cx, camera.cy), 1e-6));
  }
}

}  // namespace p2n::testing
