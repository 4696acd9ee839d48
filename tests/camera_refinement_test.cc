// Camera refinement's pieces: the corrected ray and its gradient, the corrected camera, the common motion taken
// out, and the Jacobian from world points to the field's cube that carries the field's gradient to the rays.

#include <catch2/catch.hpp>

#include <random>

#include "examples/synthetic_scene.h"
#include "nerf/camera_refinement.h"
#include "nerf/nerf_model.h"

namespace p2n::testing {
namespace {

std::vector<float> RandomCorrections(size_t views, float rotation, float shift, uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  std::vector<float> values(views * kPoseParams);
  for (size_t k = 0; k < values.size(); ++k) values[k] = (k % kPoseParams < 3 ? rotation : shift) * normal(random);
  return values;
}

}  // namespace

TEST_CASE("a corrected ray's gradient matches finite differences, at zero and at a large correction",
          "[camera_refinement]") {
  const Ray ray{Eigen::Vector3d(0.3, -1.2, 2.0), Eigen::Vector3d(0.2, 0.5, -0.8).normalized()};
  // L = a . origin' + b . direction' for fixed a, b.
  const Eigen::Vector3d a(0.7, -0.4, 1.1), b(-0.3, 0.9, 0.5);
  const auto loss = [&](const float* correction) {
    const Ray corrected = CorrectRay(correction, ray);
    return a.dot(corrected.origin) + b.dot(corrected.direction);
  };
  for (const float size : {0.0f, 0.4f}) {
    float correction[kPoseParams] = {size, -0.5f * size, 0.8f * size, 0.1f, -0.2f, 0.3f};
    float analytic[kPoseParams] = {};
    CorrectRayBackward(correction, CorrectRay(correction, ray).direction, a, b, analytic);
    for (int k = 0; k < kPoseParams; ++k) {
      const float saved = correction[k], h = 1e-3f;
      correction[k] = saved + h;
      const double plus = loss(correction);
      correction[k] = saved - h;
      const double minus = loss(correction);
      correction[k] = saved;
      CHECK(analytic[k] == Approx((plus - minus) / (2 * h)).margin(1e-3));
    }
  }
}

TEST_CASE("a corrected camera casts the corrected rays", "[camera_refinement]") {
  const PinholeCamera camera = LookAtCamera(Eigen::Vector3d(2, -3, 1), Eigen::Vector3d::Zero(), 64, 48, 50);
  const float correction[kPoseParams] = {0.05f, -0.02f, 0.1f, 0.3f, 0.1f, -0.2f};
  const PinholeCamera corrected = CorrectedCamera(camera, correction);
  for (const Eigen::Vector2d& pixel : {Eigen::Vector2d(0.5, 0.5), Eigen::Vector2d(40.2, 13.7)}) {
    const Ray expected = CorrectRay(correction, CameraRay(camera, pixel.x(), pixel.y()));
    const Ray ray = CameraRay(corrected, pixel.x(), pixel.y());
    CHECK((ray.origin - expected.origin).norm() < 1e-6);
    CHECK((ray.direction - expected.direction).norm() < 1e-6);
  }
  CHECK(CorrectionDegrees(correction) == Approx(std::sqrt(0.05 * 0.05 + 0.02 * 0.02 + 0.1 * 0.1) * 180 / M_PI));
  CHECK(CorrectionShift(correction) == Approx(std::sqrt(0.09 + 0.01 + 0.04)));
}

TEST_CASE("the common motion of all cameras is taken out, and what differs between them is kept",
          "[camera_refinement]") {
  std::vector<Eigen::Vector3d> centres;
  for (int i = 0; i < 8; ++i) centres.emplace_back(2 * std::cos(i), 2 * std::sin(i), 0.3 * i - 1);
  // A similarity of all cameras alike: a small rotation about the origin, a scale and a shift.
  const Eigen::Vector3d w(0.01, -0.02, 0.015), u(0.05, 0.02, -0.03);
  const double s = 0.02;
  std::vector<float> common(centres.size() * kPoseParams);
  for (size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Vector3d shift = w.cross(centres[i]) + s * centres[i] + u;
    for (int k = 0; k < 3; ++k) {
      common[i * kPoseParams + k] = static_cast<float>(w[k]);
      common[i * kPoseParams + 3 + k] = static_cast<float>(shift[k]);
    }
  }
  std::vector<float> removed = common;
  RemoveCommonMotion(centres, &removed);
  for (const float value : removed) CHECK(std::abs(value) < 1e-6);
  // Corrections with no common part come back unchanged, with the common part added too.
  std::vector<float> own = RandomCorrections(centres.size(), 0.01f, 0.03f, 3);
  RemoveCommonMotion(centres, &own);
  std::vector<float> mixed(own.size());
  for (size_t k = 0; k < own.size(); ++k) mixed[k] = own[k] + common[k];
  RemoveCommonMotion(centres, &mixed);
  for (size_t k = 0; k < own.size(); ++k) CHECK(mixed[k] == Approx(own[k]).margin(1e-6));
  double size = 0;
  for (const float value : own) size += std::abs(value);
  CHECK(size > 0.05);
}

TEST_CASE("the field point's Jacobian matches finite differences in every scene space", "[camera_refinement]") {
  NerfModel model;
  model.forward.cam_from_world = LookAtCamera(Eigen::Vector3d(0, -3, 0.5), Eigen::Vector3d::Zero(), 4, 4, 60)
                                     .world_from_cam.block<3, 3>(0, 0)
                                     .transpose();
  model.forward.centre = Eigen::Vector3d(0, -3, 0.5);
  model.forward.near = 0.5;
  model.forward.tan_x = 0.6;
  model.forward.tan_y = 0.45;
  const std::vector<Eigen::Vector3d> points = {{0.3, -0.2, 0.5}, {2.5, 0.4, -1.1}, {-0.5, 7.0, 3.0}};
  for (const SceneSpace space : {SceneSpace::kBounded, SceneSpace::kUnbounded, SceneSpace::kForward}) {
    model.space = space;
    for (const Eigen::Vector3d& point : points) {
      INFO(SceneSpaceName(space) << " at " << point.transpose());
      const Eigen::Matrix3d jacobian = FieldPointJacobian(model, point);
      for (int axis = 0; axis < 3; ++axis) {
        const double h = 1e-6;
        const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(axis);
        const Eigen::Vector3d numeric = (FieldPoint(model, point + step) - FieldPoint(model, point - step)) / (2 * h);
        CHECK((jacobian.col(axis) - numeric).norm() < 1e-6);
      }
    }
  }
}

}  // namespace p2n::testing
