#pragma once
// A field with a known surface for the mesh tests: a sphere whose density crosses kThreshold exactly at its radius,
// coloured by the direction it is seen from.

#include <algorithm>
#include <memory>

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

}  // namespace p2n::testing
