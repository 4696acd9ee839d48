#pragma once
// The `ngp` radiance field (instant-ngp's design): a multiresolution hash grid over the unit cube, a density
// MLP (one hidden layer of 64) whose first output is the log-density and whose others are geometry features,
// and a colour MLP (two hidden layers of 64) fed the features and the view direction's spherical harmonics.
// Density = exp(clamped log-density): the clamp keeps it finite (at most e^kMaxLogDensity) and its gradient
// bounded.

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <memory>

#include "nerf/encoding.h"
#include "nerf/mlp.h"

namespace p2n {

struct NgpFieldConfig {
  HashGridConfig grid;
  int geometry_features = 15;  // density MLP outputs besides the log-density
  int width = 64;
  int density_hidden_layers = 1;
  int colour_hidden_layers = 2;

  nlohmann::json ToJson() const;
};

template <typename T>
class NgpField {
 public:
  using Matrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;
  static constexpr T kMaxLogDensity = T(15);  // density at most ~3.3e6 per unit length

  // Activations of one Forward(), kept for Backward().
  struct Cache {
    Matrix positions, encoded, density_out, colour_in;
    typename Mlp<T>::Cache density_cache, colour_cache;
  };

  NgpField(const NgpFieldConfig& config, uint64_t seed);

  // positions and directions: 3 x n (positions in [0, 1]^3, directions of unit length). Writes density (1 x n)
  // and rgb (3 x n, in (0, 1)).
  void Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb, Cache* cache) const;
  // Given dL/d(density) and dL/d(rgb): adds the MLPs' gradients into `d_density_mlp` and `d_colour_mlp` and
  // accumulates the grid's (after grid().ZeroGrad() at the start of a step).
  void Backward(const Cache& cache, const Matrix& d_density, const Matrix& d_rgb, T* d_density_mlp,
                T* d_colour_mlp);

  HashGridEncoding<T>& grid() { return grid_; }
  Mlp<T>& density_mlp() { return density_mlp_; }
  Mlp<T>& colour_mlp() { return colour_mlp_; }
  nlohmann::json Config() const;

 private:
  NgpFieldConfig config_;
  HashGridEncoding<T> grid_;
  Mlp<T> density_mlp_, colour_mlp_;
};

extern template class NgpField<float>;
extern template class NgpField<double>;

}  // namespace p2n
