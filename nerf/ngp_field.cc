#include "nerf/ngp_field.h"

#include <algorithm>
#include <cmath>

#include "nerf/spherical_harmonics.h"

namespace p2n {
namespace {

MlpConfig DensityConfig(const NgpFieldConfig& config) {
  return {config.grid.levels * config.grid.features_per_level, 1 + config.geometry_features, config.width,
          config.density_hidden_layers, OutputActivation::kNone};
}

MlpConfig ColourConfig(const NgpFieldConfig& config) {
  return {config.geometry_features + kSphericalHarmonicsCount, 3, config.width, config.colour_hidden_layers,
          OutputActivation::kSigmoid};
}

}  // namespace

nlohmann::json NgpFieldConfig::ToJson() const {
  return {{"otype", "NgpField"},
          {"encoding", grid.ToJson()},
          {"direction_encoding", {{"otype", "SphericalHarmonics"}, {"degree", 4}}},
          {"density_network", DensityConfig(*this).ToJson()},
          {"colour_network", ColourConfig(*this).ToJson()},
          {"density_activation", "exp(min(x, 15))"}};
}

template <typename T>
NgpField<T>::NgpField(const NgpFieldConfig& config, uint64_t seed)
    : config_(config),
      grid_(3, config.grid, seed),
      density_mlp_(DensityConfig(config), seed + 1),
      colour_mlp_(ColourConfig(config), seed + 2) {}

template <typename T>
nlohmann::json NgpField<T>::Config() const {
  return config_.ToJson();
}

template <typename T>
void NgpField<T>::Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb,
                          Cache* cache) const {
  const Eigen::Index n = positions.cols();
  cache->positions = positions;
  grid_.Forward(positions, &cache->encoded);
  density_mlp_.Forward(cache->encoded, &cache->density_out, &cache->density_cache);
  density->resize(1, n);
  for (Eigen::Index i = 0; i < n; ++i) (*density)(0, i) = std::exp(std::min(cache->density_out(0, i), kMaxLogDensity));
  cache->colour_in.resize(config_.geometry_features + kSphericalHarmonicsCount, n);
  cache->colour_in.topRows(config_.geometry_features) = cache->density_out.bottomRows(config_.geometry_features);
  for (Eigen::Index i = 0; i < n; ++i) {
    SphericalHarmonics(directions(0, i), directions(1, i), directions(2, i),
                       cache->colour_in.col(i).data() + config_.geometry_features);
  }
  colour_mlp_.Forward(cache->colour_in, rgb, &cache->colour_cache);
}

template <typename T>
void NgpField<T>::Backward(const Cache& cache, const Matrix& d_density, const Matrix& d_rgb, T* d_density_mlp,
                           T* d_colour_mlp) {
  Matrix d_colour_in;
  colour_mlp_.Backward(cache.colour_cache, d_rgb, d_colour_mlp, &d_colour_in);
  Matrix d_density_out(cache.density_out.rows(), cache.density_out.cols());
  d_density_out.bottomRows(config_.geometry_features) = d_colour_in.topRows(config_.geometry_features);
  for (Eigen::Index i = 0; i < cache.density_out.cols(); ++i) {
    const T raw = cache.density_out(0, i);
    // d exp(min(x, max)) / dx = exp(x) below the clamp, 0 above it.
    d_density_out(0, i) = raw < kMaxLogDensity ? d_density(0, i) * std::exp(raw) : T(0);
  }
  Matrix d_encoded;
  density_mlp_.Backward(cache.density_cache, d_density_out, d_density_mlp, &d_encoded);
  grid_.Backward(cache.positions, d_encoded);
}

template class NgpField<float>;
template class NgpField<double>;

}  // namespace p2n
