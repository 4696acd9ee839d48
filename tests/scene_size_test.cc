// How large a scene is against what a view sees (splat/scene_size.h): the share of the splats a view's picture holds.

#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include "examples/synthetic_scene.h"
#include "splat/scene_size.h"

namespace p2n::testing {
namespace {

// `points` as splats (their means only matter here).
Gaussians<float> SplatsAt(const std::vector<Eigen::Vector3d>& points) {
  Gaussians<float> splats;
  splats.sh_degree = 0;
  splats.Resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    for (int a = 0; a < 3; ++a) splats.positions[3 * i + a] = static_cast<float>(points[i][a]);
  }
  return splats;
}

// A camera at `x` along the x axis, 10 above the line y = z = 0, looking straight down: 100 pixels wide, fx 50, so
// that its picture holds the line from x - 10 to x + 10.
TrainView LookingDownAt(double x) {
  TrainView view;
  view.camera.width = 100;
  view.camera.height = 20;
  view.camera.fx = view.camera.fy = 50;
  view.camera.cx = 50;
  view.camera.cy = 10;
  view.camera.world_from_cam.topRightCorner<3, 1>() = Eigen::Vector3d(x, 0, 10);  // looks along -z: down
  return view;
}

}  // namespace

TEST_CASE("A view's share of the scene: the splats its picture holds in front of it, averaged over the views",
          "[splat]") {
  // 1,000 splats one apart along the line, at 0.5, 1.5, ...: each camera's picture holds 20 of them.
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 1000; ++i) points.emplace_back(i + 0.5, 0, 0);
  const Gaussians<float> line = SplatsAt(points);
  const std::vector<TrainView> views = {LookingDownAt(100), LookingDownAt(500)};
  CHECK(MeanViewShare(views, line, 0.01) == Approx(0.02));
  // A camera by the end of the line sees half as many; one below it (the splats behind it) none.
  TrainView below = LookingDownAt(300);
  below.camera.world_from_cam.topRightCorner<3, 1>().z() = -10;
  CHECK(MeanViewShare({LookingDownAt(0), below}, line, 0.01) == Approx(0.005));
  CHECK(InPicture(views[0].camera, &line.positions[3 * 95], 0.01));
  CHECK_FALSE(InPicture(views[0].camera, &line.positions[3 * 115], 0.01));
  // Beyond the near plane only.
  CHECK(MeanViewShare(views, line, 11) == 0);
  CHECK(MeanViewShare(views, Gaussians<float>{}, 0.01) == 1);
  CHECK(MeanViewShare({}, line, 0.01) == 1);
}

TEST_CASE("The synthetic survey's views each see a small part of the scene, its orbit's most of it", "[splat]") {
  const Gaussians<float> surface = SplatsAt(SyntheticSurfacePoints(0.05));
  const auto share = [&](const std::string& path) {
    SyntheticSceneOptions options;
    options.path = path;
    options.num_views = 49;
    std::vector<TrainView> views;
    for (const PinholeCamera& camera : SyntheticCameras(options)) {
      views.emplace_back();
      views.back().camera = camera;
    }
    return MeanViewShare(views, surface, 0.01);
  };
  const double survey = share("survey"), orbit = share("orbit");
  INFO("survey " << survey << ", orbit " << orbit);
  CHECK(survey < 0.25);
  CHECK(survey > 0.02);
  CHECK(orbit > 0.5);
}

}  // namespace p2n::testing
