// The synthetic scene: camera conventions and a deterministic, textured rendering.

#include <OpenImageIO/imagebufalgo.h>
#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include <fstream>

#include "base/camera.h"
#include "examples/synthetic_scene.h"
#include "tests/test_util.h"

namespace p2n::testing {

TEST_CASE("look-at cameras: a proper rotation, the target at the image centre, up is up", "[synthetic]") {
  const PinholeCamera camera = LookAtCamera({3, -2, 1.5}, {0, 0, 0.4}, 320, 240, 60);
  const Eigen::Matrix3d rotation = camera.world_from_cam.block<3, 3>(0, 0);
  CHECK((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() < 1e-12);
  CHECK(rotation.determinant() == Approx(1.0));
  const Eigen::Vector2d centre = Project(camera, {0, 0, 0.4});
  CHECK(centre.x() == Approx(160.0));
  CHECK(centre.y() == Approx(120.0));
  // A point above the target appears higher in the image (smaller row).
  CHECK(Project(camera, {0, 0, 0.9}).y() < 120.0);
  // 60 degrees horizontal field of view: fx = 160 / tan(30 degrees).
  CHECK(camera.fx == Approx(160.0 / std::tan(30.0 * M_PI / 180)));
}

TEST_CASE("the synthetic scene renders deterministically, with texture, and writes its true cameras", "[synthetic]") {
  SyntheticSceneOptions options;
  options.num_views = 3;
  options.width = 64;
  options.height = 48;
  const std::vector<PinholeCamera> cameras = SyntheticCameras(options);
  REQUIRE(cameras.size() == 3);
  for (const PinholeCamera& camera : cameras) {
    CHECK((camera.world_from_cam.block<3, 1>(0, 3) - Eigen::Vector3d(0, 0, 0.4)).norm() == Approx(options.radius));
  }
  const OIIO::ImageBuf a = RenderSyntheticView(cameras[0], 1);
  const OIIO::ImageBuf b = RenderSyntheticView(cameras[0], 1);
  CHECK(OIIO::ImageBufAlgo::compare(a, b, 0, 0).maxerror == 0.0);
  const auto stats = OIIO::ImageBufAlgo::computePixelStats(a);
  for (int c = 0; c < 3; ++c) {
    CHECK(stats.avg[c] > 0.2);
    CHECK(stats.avg[c] < 0.9);
    CHECK(stats.stddev[c] > 0.05);  // textured, not flat
  }
  TempDir dir;
  WriteSyntheticScene(options, dir.path());
  std::ifstream in(dir / "ground_truth_cameras.json");
  const nlohmann::json truth = nlohmann::json::parse(in);
  REQUIRE(truth["frames"].size() == 3);
  CHECK(truth["frames"][2]["file_path"] == "view_002.png");
  CHECK(truth["frames"][2]["transform_matrix"][0][3].get<double>() == Approx(cameras[2].world_from_cam(0, 3)));
  CHECK(std::filesystem::exists(dir / "view_001.png"));
}

}  // namespace p2n::testing
