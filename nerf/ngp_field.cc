#include "nerf/ngp_field.h"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <utility>

#include "base/declared_fields.h"
#include "nerf/render_mlp.h"
#include "nerf/spherical_harmonics.h"

namespace p2n {
namespace {

int EncodedFeatures(const NgpFieldConfig& config) {
  return config.planes ? config.planes->levels * config.planes->features_per_level
                       : config.grid.levels * config.grid.features_per_level;
}

MlpConfig DensityConfig(const NgpFieldConfig& config) {
  return {EncodedFeatures(config), 1 + config.geometry_features, config.width, config.density_hidden_layers,
          OutputActivation::kNone};
}

MlpConfig ColourConfig(const NgpFieldConfig& config) {
  return {config.geometry_features + kSphericalHarmonicsCount, 3, config.width, config.colour_hidden_layers,
          OutputActivation::kSigmoid};
}

template <typename T>
std::unique_ptr<Encoding<T>> MakeEncoding(const NgpFieldConfig& config, uint64_t seed) {
  if (config.planes) return std::make_unique<PlaneGridEncoding<T>>(*config.planes, seed);
  return std::make_unique<HashGridEncoding<T>>(3, config.grid, seed);
}

template <typename T, typename Matrix>
void ExpDensity(const Matrix& raw, Matrix* density) {
  density->resize(1, raw.cols());
  for (Eigen::Index i = 0; i < raw.cols(); ++i)
    (*density)(0, i) = std::exp(std::min(raw(0, i), NgpField<T>::kMaxLogDensity));
}

}  // namespace

nlohmann::json NgpFieldConfig::ToJson() const {
  nlohmann::json json = FieldsToJson(*this);
  json["otype"] = "NgpField";
  json["encoding"] = planes ? planes->ToJson() : grid.ToJson();
  json["direction_encoding"] = {{"otype", "SphericalHarmonics"}, {"degree", 4}};
  json["density_network"] = DensityConfig(*this).ToJson();
  json["colour_network"] = ColourConfig(*this).ToJson();
  json["density_activation"] = "exp(min(x, 15))";
  return json;
}

NgpFieldConfig NgpFieldConfig::FromJson(const nlohmann::json& json) {
  NgpFieldConfig config;
  ReadFields(json, &config,
             {"otype", "encoding", "direction_encoding", "density_network", "colour_network", "density_activation"},
             "NgpField config");
  if (json.contains("encoding")) {
    const nlohmann::json& encoding = json.at("encoding");
    if (encoding.is_object() && encoding.value("otype", "") == "Planes") {
      config.planes = PlaneGridConfig::FromJson(encoding);
    } else {
      config.grid = HashGridConfig::FromJson(encoding);
    }
  }
  CheckDerivedKeys(json, config.ToJson(),
                   {"direction_encoding", "density_network", "colour_network", "density_activation"},
                   "NgpField config");
  return config;
}

template <typename T>
NgpField<T>::NgpField(const NgpFieldConfig& config, uint64_t seed)
    : config_(config),
      encoding_(MakeEncoding<T>(config, seed)),
      density_mlp_(DensityConfig(config), seed + 1),
      colour_mlp_(ColourConfig(config), seed + 2) {}

template <typename T>
void NgpField<T>::Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb,
                          Cache* cache) const {
  Matrix encoded;
  encoding_->Forward(positions, &encoded);
  ForwardEncoded(positions, std::move(encoded), directions, density, rgb, cache);
}

template <typename T>
void NgpField<T>::ForwardEncoded(const Matrix& positions, Matrix encoded, const Matrix& directions, Matrix* density,
                                 Matrix* rgb, Cache* cache) const {
  cache->positions = positions;
  cache->mlps.resize(2);
  // The encoding, the hidden features and the colour network's input are kept once, in the networks' caches.
  const Matrix& hidden = density_mlp_.Forward(std::move(encoded), &cache->mlps[0]);
  ExpDensity<T>(hidden, density);
  Matrix colour_in;
  ColourInput(hidden, directions, &colour_in);
  *rgb = colour_mlp_.Forward(std::move(colour_in), &cache->mlps[1]);
}

template <typename T>
void NgpField<T>::ColourInput(const Matrix& hidden, const Matrix& directions, Matrix* colour_in) const {
  const Eigen::Index n = hidden.cols();
  colour_in->resize(config_.geometry_features + kSphericalHarmonicsCount, n);
  colour_in->topRows(config_.geometry_features) = hidden.bottomRows(config_.geometry_features);
  for (Eigen::Index i = 0; i < n; ++i) {
    SphericalHarmonics(directions(0, i), directions(1, i), directions(2, i),
                       colour_in->col(i).data() + config_.geometry_features);
  }
}

template <typename T>
void NgpField<T>::Render(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb) const {
  if constexpr (std::is_same_v<T, float>) {
    if (RenderMlp::Available()) {
      Matrix encoded, hidden(density_mlp_.config().outputs, positions.cols()), colour_in;
      encoding_->Forward(positions, &encoded);
      RenderMlp(density_mlp_).Forward(encoded.data(), encoded.cols(), hidden.data());
      ExpDensity<T>(hidden, density);
      ColourInput(hidden, directions, &colour_in);
      rgb->resize(colour_mlp_.config().outputs, positions.cols());
      RenderMlp(colour_mlp_).Forward(colour_in.data(), colour_in.cols(), rgb->data());
      return;
    }
  }
  RadianceField<T>::Render(positions, directions, density, rgb);
}

template <typename T>
void NgpField<T>::Density(const Matrix& positions, Matrix* density) const {
  Matrix encoded;
  typename Mlp<T>::Cache cache;
  encoding_->Forward(positions, &encoded);
  ExpDensity<T>(density_mlp_.Forward(std::move(encoded), &cache), density);
}

template <typename T>
void NgpField<T>::Backward(const Cache& cache, const Matrix& d_density, const Matrix& d_rgb, T* d_dense,
                           Matrix* d_encoded) const {
  Matrix d_colour_in;
  colour_mlp_.Backward(cache.mlps[1], d_rgb, d_dense + density_mlp_.num_params(), &d_colour_in,
                       config_.geometry_features);
  const Matrix& hidden = cache.mlps[0].activations.back();
  Matrix d_hidden(hidden.rows(), hidden.cols());
  d_hidden.bottomRows(config_.geometry_features) = d_colour_in.topRows(config_.geometry_features);
  for (Eigen::Index i = 0; i < hidden.cols(); ++i) {
    const T raw = hidden(0, i);
    // d exp(min(x, max)) / dx = exp(x) below the clamp, 0 above it.
    d_hidden(0, i) = raw < kMaxLogDensity ? d_density(0, i) * std::exp(raw) : T(0);
  }
  density_mlp_.Backward(cache.mlps[0], d_hidden, d_dense, d_encoded);
}

template <typename T>
std::vector<ParamBlock<T>> NgpField<T>::DenseParams() {
  return {{density_mlp_.params(), static_cast<size_t>(density_mlp_.num_params())},
          {colour_mlp_.params(), static_cast<size_t>(colour_mlp_.num_params())}};
}

template class NgpField<float>;
template class NgpField<double>;

}  // namespace p2n
