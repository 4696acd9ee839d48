// Forward-facing scenes: the reference camera's normalised device coordinates (analytic points), rays that stay
// straight in them, the frame fitted to a set of cameras, samples even in NDC, and the model file keeping it.

#include <catch2/catch.hpp>

#include <cmath>

#include "nerf/forward_space.h"
#include "nerf/make_field.h"
#include "nerf/nerf_model.h"
#include "nerf/ngp_field.h"
#include "nerf/renderer.h"
#include "test_camera.h"

namespace p2n::testing {
namespace {

// A reference camera at the origin looking down -z, near plane at depth 1, half-widths of slope 0.5 and 0.25.
ForwardFrame SimpleFrame() {
  ForwardFrame frame;
  frame.near = 1;
  frame.tan_x = 0.5;
  frame.tan_y = 0.25;
  return frame;
}

// Cameras side by side 0.1 apart, looking down -z (one turned 4 degrees about y), 2 units in front of the origin.
std::vector<PinholeCamera> SideBySide() {
  std::vector<PinholeCamera> cameras;
  for (int i = 0; i < 5; ++i) {
    PinholeCamera camera = CentredCamera(64, 48, 50);
    const Eigen::AngleAxisd turn(i == 4 ? 4 * M_PI / 180 : 0, Eigen::Vector3d::UnitY());
    camera.world_from_cam.topLeftCorner<3, 3>() = turn.toRotationMatrix();
    camera.world_from_cam.topRightCorner<3, 1>() = Eigen::Vector3d(0.1 * i - 0.2, 0.05 * (i % 2), 2);
    cameras.push_back(camera);
  }
  return cameras;
}

TEST_CASE("NDC: the near plane at z' = -1, infinity at 1, the frustum's edges at x', y' = +-1", "[forward]") {
  const ForwardFrame frame = SimpleFrame();
  CHECK(ForwardNdc(frame, {0, 0, -1}).isApprox(Eigen::Vector3d(0, 0, -1)));
  CHECK(ForwardNdc(frame, {0, 0, -2}).isApprox(Eigen::Vector3d(0, 0, 0)));
  CHECK(ForwardNdc(frame, {0, 0, -1e12}).z() == Approx(1.0));
  CHECK(ForwardNdc(frame, {0.5, 0.25, -1}).isApprox(Eigen::Vector3d(1, 1, -1)));
  CHECK(ForwardNdc(frame, {-4, 1, -8}).isApprox(Eigen::Vector3d(-1, 0.5, 0.75)));
  // Behind the camera and on its plane: outside the cube, finite.
  CHECK(ForwardNdc(frame, {0, 0, 1}).z() < -1);
  CHECK(ForwardNdc(frame, {1, 1, 0}).allFinite());
}

TEST_CASE("NDC: a ray stays straight, and its fraction and distance are inverse", "[forward]") {
  const ForwardFrame frame = SimpleFrame();
  const Ray ray{{0.1, -0.05, 0.5}, Eigen::Vector3d(0.3, 0.1, -1).normalized()};
  const ForwardRay forward = ToForward(frame, ray);
  REQUIRE(forward.valid);
  CHECK(forward.start.z() == Approx(-1.0));  // it starts on the near plane
  CHECK(forward.end.z() == 1.0);
  for (const double s : {0.0, 0.1, 0.5, 0.9, 0.999}) {
    const double t = forward.Distance(s);
    INFO("s = " << s);
    CHECK(forward.Fraction(t) == Approx(s).margin(1e-12));
    const Eigen::Vector3d expected = forward.start + s * (forward.end - forward.start);
    CHECK((ForwardNdc(frame, ray.origin + t * ray.direction) - expected).norm() < 1e-9);
  }
  // A ray that never gets deeper has no NDC segment; one starting beyond the near plane starts where it is.
  CHECK_FALSE(ToForward(frame, {{0, 0, 0}, {1, 0, 0}}).valid);
  CHECK_FALSE(ToForward(frame, {{0, 0, -3}, {0, 0, 1}}).valid);
  const ForwardRay deep = ToForward(frame, {{0, 0, -3}, {0, 0, -1}});
  CHECK(deep.t0 == 0.0);
  CHECK(deep.start.z() == Approx(1 - 2.0 / 3));
}

TEST_CASE("NDC: the frame fitted to cameras looks their way and holds every ray they cast", "[forward]") {
  const std::vector<PinholeCamera> cameras = SideBySide();
  const std::vector<double> nears = {1.0, 1.2, -1, 0.9, 1.1};  // one unknown
  const ForwardFrame frame = FitForwardFrame(cameras, nears);
  CHECK((frame.cam_from_world.row(2).transpose() - Eigen::Vector3d(0, 0, 1)).norm() < 0.02);
  CHECK((frame.cam_from_world.row(1).transpose() - Eigen::Vector3d(0, 1, 0)).norm() < 0.02);
  CHECK(frame.cam_from_world.determinant() == Approx(1.0));
  CHECK(frame.near == Approx(0.8 * 0.9).epsilon(0.01));
  double widest_x = 0, widest_y = 0;
  for (const PinholeCamera& camera : cameras) {
    for (int y = 0; y <= camera.height; y += 8) {
      for (int x = 0; x <= camera.width; x += 8) {
        const ForwardRay ray = ToForward(frame, CameraRay(camera, x, y));
        REQUIRE(ray.valid);
        for (const Eigen::Vector3d& p : {ray.start, ray.end}) {
          CHECK(std::abs(p.x()) <= 1 + 1e-9);
          CHECK(std::abs(p.y()) <= 1 + 1e-9);
          widest_x = std::max(widest_x, std::abs(p.x()));
          widest_y = std::max(widest_y, std::abs(p.y()));
        }
      }
    }
  }
  CHECK(widest_x == Approx(1.0));  // no wider than needed
  CHECK(widest_y == Approx(1.0));
  CHECK_THROWS_AS(FitForwardFrame({}, {}), std::invalid_argument);
}

TEST_CASE("NDC: cameras face forward when every one looks within 15 degrees of their mean direction", "[forward]") {
  CHECK(FacesForward(SideBySide()));                       // parallel but one, turned 4 degrees
  CHECK(FacesForward(RingOfCameras({-14, 0, 14})));        // looking inwards (and down) from an arc of 28 degrees
  CHECK_FALSE(FacesForward(RingOfCameras({-16, 0, 16})));  // 15.5 degrees from the mean (they look down 14)
  CHECK(FacesForward(RingOfCameras({-16, 0, 16}), 17));
  CHECK_FALSE(FacesForward(RingOfCameras({0, 90, 180, 270})));  // all round: no mean direction
  CHECK_FALSE(FacesForward({}));
}

TEST_CASE("NDC: samples are even in NDC from the near plane to infinity, lengths in NDC", "[forward]") {
  NerfModel model;
  model.space = SceneSpace::kForward;
  model.forward = SimpleFrame();
  model.occupancy = OccupancyGrid(16);
  model.occupancy.MarkAllOccupied();
  const Ray ray{{0, 0, 0}, Eigen::Vector3d(0.1, 0.05, -1).normalized()};
  const double step = 0.02;
  const std::vector<MarchSample> samples = SampleRay(model, ray, -1, -1, step, 100000, nullptr);
  REQUIRE(samples.size() > 50);
  CHECK(samples.size() < 120);  // the NDC segment is a little over 2 long: about 2 / step samples
  CHECK(ForwardNdc(model.forward, ray.origin + samples.front().t * ray.direction).z() == Approx(-1).margin(2 * step));
  CHECK(samples.back().t > 100);
  for (size_t k = 0; k + 2 < samples.size(); ++k) {  // the last segment is cut short at infinity
    INFO("sample " << k);
    CHECK(samples[k + 1].t > samples[k].t);
    CHECK(samples[k].delta == Approx(step));
    const double gap = SamplingDistance(model, ray, samples[k + 1].t) - SamplingDistance(model, ray, samples[k].t);
    CHECK(gap == Approx(step).epsilon(1e-6));
  }
  // A near distance beyond the near plane moves the first sample there; `far` does not apply.
  const std::vector<MarchSample> from_three = SampleRay(model, ray, 3, 4, step, 100000, nullptr);
  REQUIRE_FALSE(from_three.empty());
  CHECK(from_three.front().t >= 3);
  CHECK(from_three.back().t > 100);
}

TEST_CASE("NDC: model.bin keeps the scene space and the frame, and a damaged frame is refused", "[forward]") {
  NerfModel model;
  model.field = MakeField<float>(NgpFieldConfig{}.ToJson(), 1);
  model.march_step = 0.01;
  model.space = SceneSpace::kForward;
  model.forward = FitForwardFrame(SideBySide(), {1, 1, 1, 1, 1});
  BinaryWriter writer;
  WriteModel(model, &writer, false);
  BinaryReader reader(writer.buffer(), "model.bin");
  const NerfModel read = ReadModel(&reader);
  CHECK(read.space == SceneSpace::kForward);
  CHECK(read.forward.cam_from_world.isApprox(model.forward.cam_from_world));
  CHECK(read.forward.centre.isApprox(model.forward.centre));
  CHECK(read.forward.near == model.forward.near);
  CHECK(read.forward.tan_x == model.forward.tan_x);
  nlohmann::json json = ForwardFrameJson(model.forward);
  CHECK(ForwardFrameFromJson(json).tan_y == model.forward.tan_y);
  json["near"] = 0;
  CHECK_THROWS_WITH(ForwardFrameFromJson(json), Catch::Contains("near"));
  json = ForwardFrameJson(model.forward);
  json["cam_from_world"][0] = 2;
  CHECK_THROWS_WITH(ForwardFrameFromJson(json), Catch::Contains("rotation"));
  CHECK(SceneSpaceFromName("forward") == SceneSpace::kForward);
  CHECK_THROWS_AS(SceneSpaceFromName("sideways"), std::invalid_argument);
}

}  // namespace
}  // namespace p2n::testing
