// Camera conventions and scene normalisation: round trips, projections that agree to 1e-6 px, degenerate inputs.

#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <random>

#include "base/camera.h"
#include "base/errors.h"
#include "formats/ply.h"
#include "formats/scene_normalization.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace {

// COLMAP's projection with a PINHOLE camera: OpenCV axes, pixel centre of (0, 0) at (0.5, 0.5).
Eigen::Vector2d ColmapProject(const Eigen::Quaterniond& q, const Eigen::Vector3d& t, double fx, double fy, double cx,
                              double cy, const Eigen::Vector3d& point) {
  const Eigen::Vector3d p = q * point + t;
  return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
}

bool AllFinite(const Normalization& n) { return n.normalized_from_world.allFinite() && std::isfinite(n.scale); }

}  // namespace

TEST_CASE("COLMAP cam_from_world and OpenGL world_from_cam: round trip and the same pixels", "[poses]") {
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> uniform(-1, 1);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Quaterniond q =
        Eigen::Quaterniond(uniform(random), uniform(random), uniform(random), uniform(random)).normalized();
    const Eigen::Vector3d t(uniform(random), uniform(random), uniform(random) + 4);
    PinholeCamera camera{640, 480, 500 + 100 * uniform(random), 510, 321.5, 238.25, WorldFromOpenGlCamera(q, t)};
    Eigen::Quaterniond q2;
    Eigen::Vector3d t2;
    OpenCvCamFromWorld(camera.world_from_cam, &q2, &t2);
    CHECK(q2.angularDistance(q) < 1e-12);
    CHECK((t2 - t).norm() < 1e-12);
    // A point in front of the camera: both projections agree.
    const Eigen::Vector3d in_cv(uniform(random), uniform(random), 2 + uniform(random));
    const Eigen::Vector3d point = q.inverse() * (in_cv - t);
    double depth = 0;
    const Eigen::Vector2d ours = Project(camera, point, &depth);
    const Eigen::Vector2d colmap = ColmapProject(q, t, camera.fx, camera.fy, camera.cx, camera.cy, point);
    CHECK((ours - colmap).norm() < 1e-6);
    CHECK(depth == Approx(in_cv.z()));
  }
  CHECK(OpenGlFromOpenCvCamera() * OpenCvFromOpenGlCamera() == Eigen::Matrix3d::Identity());
}

TEST_CASE("normalisation: an orbit is centred, turned upright, scaled, and inverts exactly", "[poses]") {
  // Cameras on a tilted ring around (5, -3, 2), looking at it, with up vectors along the ring's normal.
  const Eigen::Vector3d target(5, -3, 2);
  const Eigen::Vector3d normal = Eigen::Vector3d(0.3, 0.2, 1).normalized();
  const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u);
  std::vector<Eigen::Vector3d> centres, ups, axes, points;
  for (int i = 0; i < 12; ++i) {
    const double angle = 2 * M_PI * i / 12;
    const Eigen::Vector3d centre = target + 10 * (std::cos(angle) * u + std::sin(angle) * v) + 3 * normal;
    centres.push_back(centre);
    axes.push_back((target - centre).normalized());
    ups.push_back(axes.back().cross(normal).cross(axes.back()).normalized());  // n - a (a . n)
  }
  std::mt19937_64 random(1);
  std::normal_distribution<double> noise(0, 0.5);
  for (int i = 0; i < 200; ++i) points.push_back(target + Eigen::Vector3d(noise(random), noise(random), noise(random)));
  const Normalization n = NormalizeScene(centres, ups, axes, points);
  CHECK(n.centre_from == "focus point");
  CHECK(n.up_from == "camera up vectors");
  const Eigen::Vector3d centred = (n.normalized_from_world * target.homogeneous()).head<3>();
  CHECK(centred.norm() < 1e-9);
  const Eigen::Vector3d up = n.normalized_from_world.topLeftCorner<3, 3>() * normal / n.scale;
  CHECK(up.z() > 0.99);
  // 95% of the points within the unit cube.
  int inside = 0;
  for (const auto& p : points)
    inside += (n.normalized_from_world * p.homogeneous()).head<3>().cwiseAbs().maxCoeff() <= 1.0 + 1e-9;
  CHECK(inside >= 190);
  CHECK((n.normalized_from_world.inverse() * n.normalized_from_world - Eigen::Matrix4d::Identity()).norm() < 1e-12);
}

TEST_CASE("normalisation of degenerate inputs: a fallback or a clear error, never NaN", "[poses]") {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ(), x = Eigen::Vector3d::UnitX();
  SECTION("no camera") { CHECK_THROWS_AS(NormalizeScene({}, {}, {}, {}), UserError); }
  SECTION("one camera and no points") {
    CHECK_THROWS_WITH(NormalizeScene({{1, 2, 3}}, {z}, {x}, {}), Catch::Contains("from different positions"));
  }
  SECTION("every camera at one point, no points") {
    CHECK_THROWS_AS(NormalizeScene({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}}, {z, z, z}, {x, -x, x}, {}), UserError);
  }
  SECTION("collinear cameras with parallel axes (forward-facing): centre and scale from the cameras") {
    const Normalization n =
        NormalizeScene({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {z, z, z},
                       {-Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY()}, {});
    CHECK(AllFinite(n));
    CHECK(n.centre_from == "cameras");
    CHECK(n.scale == Approx(2.0));  // centre (1, 0, 0); half the largest camera distance is 0.5
  }
  SECTION("up vectors that cancel out: up from the cameras' plane") {
    const Normalization n = NormalizeScene({{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}}, {z, -z, x, -x},
                                           {-x, -Eigen::Vector3d::UnitY(), x, Eigen::Vector3d::UnitY()}, {});
    CHECK(AllFinite(n));
    CHECK(n.up_from == "camera plane");
  }
}

TEST_CASE("PLY point clouds round trip", "[poses]") {
  TempDir dir;
  const std::vector<ColouredPoint> points = {{{1.5f, -2, 3}, {1, 2, 3}}, {{0, 0, 0}, {255, 0, 128}}};
  // Comments may hold any text: ones holding "end_header" or "element vertex" were once taken for the header's
  // lines, and a '\r' ends a line for other readers.
  WritePly(dir / "p.ply", points, {"scene end_header", "element vertex 7", "two\r\nlines"});
  const std::vector<ColouredPoint> back = ReadPly(dir / "p.ply");
  REQUIRE(back.size() == 2);
  CHECK(back[0].position == points[0].position);
  CHECK(back[1].rgb == points[1].rgb);
  CHECK_THAT(ReadText(dir / "p.ply"), Catch::StartsWith("ply\nformat binary_little_endian 1.0\n"));
  WriteText(dir / "bad.ply", "ply\nnonsense");
  CHECK_THROWS_WITH(ReadPly(dir / "bad.ply"), Catch::Contains("bad.ply"));
  // Found by fuzzing: a vertex count that is not a number.
  WriteText(dir / "count.ply", "ply\nelement vertex e\nend_header\n");
  CHECK_THROWS_WITH(ReadPly(dir / "count.ply"), Catch::Contains("count.ply' is not a PLY point cloud"));
  CHECK(ReadText(dir / "p.ply").find("comment two  lines\n") != std::string::npos);
}

}  // namespace p2n::testing
