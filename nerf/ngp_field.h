#pragma once
// The `ngp` radiance field (instant-ngp's design): a multiresolution hash grid over the unit cube (or K-planes'
// factorised planes: `planes`), a density MLP (one hidden layer of 64) whose first output is the log-density and
// whose others are geometry features, and a colour MLP (two hidden layers of 64) fed the features and the view
// direction's spherical harmonics. Density = exp(clamped log-density): the clamp keeps it finite (at most
// e^kMaxLogDensity) and its gradient bounded.

#include <nlohmann/json.hpp>

#include <optional>

#include "nerf/plane_grid.h"
#include "nerf/radiance_field.h"

namespace p2n {

struct NgpFieldConfig {
  HashGridConfig grid;
  std::optional<PlaneGridConfig> planes;  // set: the planes encode the points instead of the grid
  int geometry_features = 15;             // density MLP outputs besides the log-density
  int width = 64;
  int density_hidden_layers = 1;
  int colour_hidden_layers = 2;

  // The integer fields (the encoding's config is written and read as its own).
  template <class V>
  void Visit(V& v) {
    v("geometry_features", geometry_features);
    v("width", width);
    v("density_hidden_layers", density_hidden_layers);
    v("colour_hidden_layers", colour_hidden_layers);
  }
  nlohmann::json ToJson() const;
  // The inverse of ToJson(); missing keys keep their defaults; std::invalid_argument for a wrong type, an unknown
  // key, or a derived key (the networks' shapes) that does not follow from the others.
  static NgpFieldConfig FromJson(const nlohmann::json& json);
  bool operator==(const NgpFieldConfig& other) const = default;
};

template <typename T>
class NgpField : public RadianceField<T> {
 public:
  using typename RadianceField<T>::Matrix;
  using typename RadianceField<T>::Cache;
  static constexpr T kMaxLogDensity = T(15);  // density at most ~3.3e6 per unit length

  NgpField(const NgpFieldConfig& config, uint64_t seed);

  nlohmann::json Config() const override { return config_.ToJson(); }
  void Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb,
               Cache* cache) const override;
  void ForwardEncoded(const Matrix& positions, Matrix encoded, const Matrix& directions, Matrix* density, Matrix* rgb,
                      Cache* cache) const override;
  void Render(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb) const override;
  void Density(const Matrix& positions, Matrix* density) const override;
  void Backward(const Cache& cache, const Matrix& d_density, const Matrix& d_rgb, T* d_dense,
                Matrix* d_encoded) const override;
  std::vector<ParamBlock<T>> DenseParams() override;
  Encoding<T>* TrainableEncoding() override { return encoding_.get(); }

  Encoding<T>& encoding() { return *encoding_; }
  Mlp<T>& density_mlp() { return density_mlp_; }
  Mlp<T>& colour_mlp() { return colour_mlp_; }

 private:
  // The colour network's input: the density network's geometry features (below its first row, the log-density)
  // over the view directions' spherical harmonics.
  void ColourInput(const Matrix& hidden, const Matrix& directions, Matrix* colour_in) const;

  NgpFieldConfig config_;
  std::unique_ptr<Encoding<T>> encoding_;
  Mlp<T> density_mlp_, colour_mlp_;
};

extern template class NgpField<float>;
extern template class NgpField<double>;

}  // namespace p2n
