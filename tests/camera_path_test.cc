// Camera paths: orbits at the asked radius and elevation looking at the centre; spirals around the capture's
// cameras looking at their focus; the placement of a ring of cameras recovered.

#include <catch2/catch.hpp>

#include <cmath>

#include "base/camera_path.h"
#include "examples/synthetic_scene.h"
#include "test_camera.h"

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

TEST_CASE("camera paths: the arc the photos cover, and an orbit there and back over it", "[path]") {
  double start = -1, sweep = -1;
  CapturedArc(RingOfCameras({40, 10, 100, 70}), 60, &start, &sweep);  // a quarter of the circle, in any order
  CHECK(start == Approx(10));
  CHECK(sweep == Approx(90));
  CapturedArc(RingOfCameras({350, 20, 5}), 60, &start, &sweep);  // across azimuth 0
  CHECK(start == Approx(350));
  CHECK(sweep == Approx(30));
  // All round: gaps of 50 and 60 degrees.
  CapturedArc(RingOfCameras({0, 50, 100, 150, 200, 250, 300}), 60, &start, &sweep);
  CHECK(start == 0);
  CHECK(sweep == 360);

  const PinholeCamera reference = LookAtCamera({3, 0, 1}, {0, 0, 0}, 80, 60, 50);
  CameraPathOptions options;
  options.frames = 20;
  options.radius = 2;
  options.start_deg = 350;
  options.sweep_deg = 30;
  const std::vector<PinholeCamera> path = OrbitPath(reference, options);
  REQUIRE(path.size() == 20);
  const auto azimuth = [&](int i) {
    const Eigen::Vector3d p = path[i].world_from_cam.block<3, 1>(0, 3);
    return std::atan2(p.y(), p.x()) * 180 / M_PI;  // 350 is -10 here
  };
  CHECK(azimuth(0) == Approx(-10));
  CHECK(azimuth(10) == Approx(20));  // the far end halfway
  for (int i = 1; i < 20; ++i) {
    CHECK(azimuth(i) > -10);
    CHECK(azimuth(i) < 20 + 1e-9);
    CHECK(path[i].world_from_cam == path[20 - i].world_from_cam);  // back the same way, exactly
    CHECK(Project(path[i], Eigen::Vector3d::Zero()).isApprox(Eigen::Vector2d(path[i].cx, path[i].cy), 1e-9));
  }
  const std::vector<size_t> first = FirstOfEqualCameras(path);
  for (int i = 0; i < 20; ++i) CHECK(first[i] == static_cast<size_t>(std::min(i, 20 - i)));
  options.sweep_deg = 360;  // all round: no repeats
  const std::vector<size_t> round = FirstOfEqualCameras(OrbitPath(reference, options));
  for (size_t i = 0; i < round.size(); ++i) CHECK(round[i] == i);
  options.sweep_deg = 0;
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
