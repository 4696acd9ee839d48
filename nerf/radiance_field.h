#pragma once
// The interface the trainer and the renderer use for any radiance field: points in the unit cube and view
// directions in, density and colour out, with gradients. A field's parameters are dense blocks (MLP weights,
// updated by dense Adam) and at most one trainable encoding (a hash grid, updated sparsely). Fields are made
// from their JSON config ("otype": "NgpField", "VanillaField", or "BlockedField" for a field by blocks), which
// Config() prints in full.

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <memory>
#include <vector>

#include "nerf/encoding.h"
#include "nerf/mlp.h"

namespace p2n {

template <typename T>
struct ParamBlock {
  T* data;
  size_t size;
};

template <typename T>
class RadianceField {
 public:
  using Matrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;

  // Activations of one Forward(), kept for Backward(); every matrix has a column per sample, or none where a
  // field does not use it (NgpField keeps its encoding and hidden features in its networks' caches alone).
  struct Cache {
    Matrix positions, encoded, hidden, colour_in;
    std::vector<typename Mlp<T>::Cache> mlps;

    // Keeps the samples `columns` (increasing, distinct) alone: Backward() with their dL/d(density) and dL/d(rgb)
    // then costs nothing for the others (e.g. the samples behind a ray's termination point, which have no
    // gradient). Keeping them all copies nothing (on real captures nearly every sample is kept).
    void KeepColumns(const std::vector<Eigen::Index>& columns) {
      if (static_cast<Eigen::Index>(columns.size()) == positions.cols()) return;
      const auto keep = [&](Matrix& m) {
        if (m.cols() > 0) m = m(Eigen::all, columns).eval();
      };
      for (Matrix* m : {&positions, &encoded, &hidden, &colour_in}) keep(*m);
      for (typename Mlp<T>::Cache& mlp : mlps) {
        for (Matrix& m : mlp.activations) keep(m);
      }
    }
  };

  virtual ~RadianceField() = default;
  virtual nlohmann::json Config() const = 0;

  // positions and directions: 3 x n (positions in [0, 1]^3, directions of unit length). Writes density (1 x n,
  // finite and >= 0) and rgb (3 x n, in (0, 1)).
  virtual void Forward(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb,
                       Cache* cache) const = 0;
  // Forward() given the trainable encoding's output for `positions` (encoded: its output_dims x n, moved into the
  // cache), computed beforehand for a whole batch at once (the trainer does, so the hash tables are read level
  // by level); a field without a trainable encoding ignores `encoded`.
  virtual void ForwardEncoded(const Matrix& positions, Matrix encoded, const Matrix& directions, Matrix* density,
                              Matrix* rgb, Cache* cache) const {
    (void)encoded;
    Forward(positions, directions, density, rgb, cache);
  }
  // Forward() for rendering: no cache for Backward(), and possibly faster and in lower precision (NgpField<float>:
  // its networks through RenderMlp where the CPU has AVX-512 BF16 or AVX2, outputs within about 1% of Forward()'s).
  virtual void Render(const Matrix& positions, const Matrix& directions, Matrix* density, Matrix* rgb) const {
    Cache cache;
    Forward(positions, directions, density, rgb, &cache);
  }
  // Density alone (for the occupancy grid and meshes).
  virtual void Density(const Matrix& positions, Matrix* density) const = 0;
  // Given dL/d(density) and dL/d(rgb): adds dL/d(dense parameters) into `d_dense` (the blocks of DenseParams()
  // one after another) and writes dL/d(encoding output) into `d_encoded` for the trainable encoding's
  // Backward(cache.positions, *d_encoded); a field without one leaves it empty.
  virtual void Backward(const Cache& cache, const Matrix& d_density, const Matrix& d_rgb, T* d_dense,
                        Matrix* d_encoded) const = 0;

  virtual std::vector<ParamBlock<T>> DenseParams() = 0;
  size_t num_dense_params() {
    size_t count = 0;
    for (const ParamBlock<T>& block : DenseParams()) count += block.size;
    return count;
  }
  // The hash grid, or null.
  virtual Encoding<T>* TrainableEncoding() { return nullptr; }
};

}  // namespace p2n
