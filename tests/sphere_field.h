#pragma once
// A field with a known surface for the mesh tests: a sphere whose density crosses kThreshold exactly at its radius,
// coloured by the direction it is seen from.

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "nerf/nerf_model.h"

namespace p2n::testing {

inline constexpr float kRadius = 0.6f, kThreshold = 25;

// Density threshold + 400 (radius - |x|) (clamped at 0), colour (1 - d) / 2 for view direction d.
class SphereField : public RadianceField<float> {
 public:
  explicit SphereField(float radius) : radius_(radius) {}
  nlohmann::json Config() const override { return {{"otype", "SphereField"}}; }
  void Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb, Cache*) const override {
    Density(positions, density);
    *rgb = (1.0f - directions.array()) * 0.5f;
  }
  void Density(const Matrix& positions, Matrix* density) const override {
    density->resize(1, positions.cols());
    for (Eigen::Index i = 0; i < positions.cols(); ++i) {
      const float r = (2 * positions.col(i).array() - 1).matrix().norm();  // the bounded box's world point
      (*density)(0, i) = std::max(0.0f, kThreshold + 400 * (radius_ - r));
    }
  }
  void Backward(const Cache&, const Matrix&, const Matrix&, float*, Matrix*) const override {}
  std::vector<ParamBlock<float>> DenseParams() override { return {}; }

 private:
  float radius_;
};

inline NerfModel SphereModel(float radius = kRadius) {
  NerfModel model;
  model.field = std::make_unique<SphereField>(radius);
  return model;  // the occupancy grid's cells are unknown: all count as occupied
}

// The volume a closed mesh wound counter-clockwise from outside encloses (negative wound the other way).
inline double SignedVolume(const std::vector<Eigen::Vector3f>& positions,
                           const std::vector<std::array<uint32_t, 3>>& triangles) {
  double volume = 0;
  for (const auto& t : triangles) volume += positions[t[0]].dot(positions[t[1]].cross(positions[t[2]])) / 6.0;
  return volume;
}

}  // namespace p2n::testing
