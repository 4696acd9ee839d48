#pragma once
// The `vanilla` radiance field: the NeRF paper's (and the seed's) model, for comparison and fidelity.
// Positions (mapped to [-1, 1]^3) get a positional encoding with L = 10 and directions one with L = 4, both
// keeping the raw input; 8 fully connected layers of 256 (ReLU) with the encoded position concatenated again
// after the 4th; a linear layer gives the density (ReLU) and a 256 feature vector; the feature and the encoded
// direction go through 128 (ReLU) to the colour (sigmoid).

#include <nlohmann/json.hpp>

#include "nerf/radiance_field.h"

namespace p2n {

struct VanillaFieldConfig {
  int position_levels = 10;
  int direction_levels = 4;
  int width = 256;
  int layers = 8;  // of `width`, split in two halves with the skip connection between them
  int colour_width = 128;

  template <class V>
  void Visit(V& v) {
    v("position_levels", position_levels);
    v("direction_levels", direction_levels);
    v("width", width);
    v("layers", layers);
    v("colour_width", colour_width);
  }
  nlohmann::json ToJson() const;
  // As NgpFieldConfig::FromJson; also layers must be even and at least 2.
  static VanillaFieldConfig FromJson(const nlohmann::json& json);
  bool operator==(const VanillaFieldConfig& other) const = default;
};

template <typename T>
class VanillaField : public RadianceField<T> {
 public:
  using typename RadianceField<T>::Matrix;
  using typename RadianceField<T>::Cache;

  VanillaField(const VanillaFieldConfig& config, uint64_t seed);

  nlohmann::json Config() const override { return config_.ToJson(); }
  void Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb,
               Cache* cache) const override;
  void Density(const Matrix& positions, Matrix* density) const override;
  void Backward(const Cache& cache, const Matrix& d_density, const Matrix& d_rgb, T* d_dense,
                Matrix* d_encoded) const override;
  std::vector<ParamBlock<T>> DenseParams() override;

 private:
  // Runs the position trunk (both halves and the head); the head's output (1 + width rows) into `head`.
  void Trunk(const Matrix& positions, Matrix* encoded, Matrix* head, typename Mlp<T>::Cache* caches) const;

  VanillaFieldConfig config_;
  PositionalEncoding<T> position_encoding_, direction_encoding_;
  Mlp<T> first_half_, second_half_, head_, colour_;
};

extern template class VanillaField<float>;
extern template class VanillaField<double>;

}  // namespace p2n
