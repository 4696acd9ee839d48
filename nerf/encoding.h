#pragma once
// Encodings map points in [0, 1]^D to feature vectors for an MLP (columns are points). Components are made
// from nested JSON-like configs with an "otype" (as in tiny-cuda-nn) and can print their full config.

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "nerf/touch_marks.h"

namespace p2n {

template <typename T>
class Encoding {
 public:
  using Matrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;

  virtual ~Encoding() = default;
  virtual int input_dims() const = 0;
  virtual int output_dims() const = 0;
  virtual nlohmann::json Config() const = 0;
  // output (output_dims x n) for input (input_dims x n). Grids clamp coordinates into [0, 1]; the positional
  // encoding takes any finite value.
  virtual void Forward(const Matrix& input, Matrix* output) const = 0;

  // Trainable encodings (a hash grid) override these; fixed ones (positional encoding) have no parameters.
  virtual size_t num_params() const { return 0; }
  virtual T* params() { return nullptr; }
  // dL/d(params): Backward() adds to it, ZeroGrad() zeroes it (so does the sparse Adam step, for the entries
  // it updates). An entry no input touched keeps a gradient of exactly zero.
  virtual T* grads() { return nullptr; }
  // Values that share one optimiser step count (the features of one table entry).
  virtual int entry_size() const { return 1; }
  // Which entries Backward() touched since the sparse Adam step cleared them (nullptr: not recorded).
  virtual TouchMarks* touched() { return nullptr; }
  virtual void ZeroGrad() {}
  // Adds dL/d(params) for `input` given dL/d(output) (output_dims x n).
  virtual void Backward(const Matrix& input, const Matrix& d_output) {
    (void)input;
    (void)d_output;
  }
  // Writes dL/d(input) (input_dims x n) given dL/d(output); a grid's is zero along an axis where it clamped the
  // coordinate. std::logic_error for an encoding without it.
  virtual void InputGradient(const Matrix& input, const Matrix& d_output, Matrix* d_input) const {
    (void)input;
    (void)d_output;
    (void)d_input;
    throw std::logic_error("this encoding has no gradient with respect to its input");
  }
};

// [x, sin(2^k pi x), cos(2^k pi x) for k < levels] per coordinate: the NeRF paper's encoding, keeping the
// raw input. levels = 0 gives the raw coordinates only.
template <typename T>
class PositionalEncoding : public Encoding<T> {
 public:
  using typename Encoding<T>::Matrix;
  PositionalEncoding(int dims, int levels);
  int input_dims() const override { return dims_; }
  int output_dims() const override { return dims_ * (1 + 2 * levels_); }
  nlohmann::json Config() const override;
  void Forward(const Matrix& input, Matrix* output) const override;

 private:
  int dims_, levels_;
};

struct HashGridConfig {
  static constexpr const char* kName = "hash_grid";  // checks name hash_grid.FIELD
  int levels = 16;                                   // resolutions, from base to finest, growing geometrically
  int features_per_level = 2;
  int log2_table_size = 19;      // entries per level (at most; coarse levels that fit are stored densely)
  int base_resolution = 16;      // cells per axis of the coarsest level
  int finest_resolution = 2048;  // cells per axis of the finest level

  template <class V>
  void Visit(V& v) {
    v("levels", levels);
    v("features_per_level", features_per_level);
    v("log2_table_size", log2_table_size);
    v("base_resolution", base_resolution);
    v("finest_resolution", finest_resolution);
  }
  // std::invalid_argument naming the field and its rule.
  void Check() const;
  nlohmann::json ToJson() const;
  // The inverse of ToJson(); missing keys keep their defaults; std::invalid_argument for an unknown key or a
  // value of the wrong type.
  static HashGridConfig FromJson(const nlohmann::json& json);
  bool operator==(const HashGridConfig& other) const = default;
};

// Multiresolution hash encoding (Mueller et al. 2022), D-linear interpolation of per-vertex features at each
// level. Each level's table is contiguous. Backward runs one level per task (no two threads write one
// entry).
template <typename T>
class HashGridEncoding : public Encoding<T> {
 public:
  using typename Encoding<T>::Matrix;
  HashGridEncoding(int dims, const HashGridConfig& config, uint64_t seed);

  int input_dims() const override { return dims_; }
  int output_dims() const override { return config_.levels * config_.features_per_level; }
  nlohmann::json Config() const override;
  void Forward(const Matrix& input, Matrix* output) const override;

  size_t num_params() const override { return params_.size(); }
  T* params() override { return params_.data(); }
  T* grads() override { return grads_.data(); }
  int entry_size() const override { return config_.features_per_level; }
  TouchMarks* touched() override { return touched_.get(); }
  void ZeroGrad() override;
  void Backward(const Matrix& input, const Matrix& d_output) override;
  void InputGradient(const Matrix& input, const Matrix& d_output, Matrix* d_input) const override;

 private:
  struct Level {
    double scale;       // a coordinate in [0, 1] maps to scale * x in grid units
    uint32_t size;      // entries
    uint32_t offset;    // first entry
    bool dense;         // indexed directly rather than hashed
    uint32_t vertices;  // vertices per axis (dense levels)
  };
  // Entry of a grid vertex at `level`.
  uint32_t EntryIndex(const Level& level, const uint32_t* vertex) const;
  // The entries of the 2^D vertices around point `p` at `level` and their interpolation weights, corner 0 to
  // 2^D - 1 (bit d of a corner set: the upper vertex along axis d).
  void Corners(const Level& level, const T* p, uint32_t* entries, T* weights) const;
  // Corners() of `count` (at most kGroup) points from column `first` of `input`, corner after corner: point i's
  // corner c at c * kGroup + i.
  void GroupCorners(const Level& level, const Matrix& input, Eigen::Index first, int count, uint32_t* entries,
                    T* weights) const;
  // Asks the cache for the `corners` entries (of `features` values) of `table` at entries[c * kGroup] (for writing
  // or reading).
  void PrefetchEntries(const uint32_t* entries, int corners, int features, const T* table, bool write) const;
  // The layouts whose level loops are compiled for them (their features and corners known, the loops unrolled):
  // 3 dimensions with 2 or 4 features per level. Fox's render: the forward loop 11% less time than with the
  // corners counted at run time.
  enum LevelLayout { kCube2, kCube4, kOther };
  LevelLayout Layout() const;
  // Forward() and Backward() at level l (kFeatures: features per level, kCorners: corners per cell; 0 for any),
  // with the features (and their gradients) level-major: level l's of point i at (l * n + i) * features_per_level.
  template <int kFeatures, int kCorners>
  void ForwardLevel(int l, const Matrix& input, Eigen::Index begin, Eigen::Index end, T* by_level) const;
  template <int kFeatures, int kCorners>
  void BackwardLevel(int l, const Matrix& input, const T* d_by_level);
  // From the level-major layout to the points' columns (output_dims() x n), or back.
  void Transpose(const T* from, Eigen::Index n, T* to, bool to_points) const;
  // Transpose() of points begin..end.
  template <int kFeatures>
  void TransposeBlock(const T* from, Eigen::Index n, Eigen::Index begin, Eigen::Index end, T* to, bool to_points) const;
  // Adds this level's dL/d(p) for one point given dL/d(this level's features).
  void AddInputGradient(const Level& level, const T* p, const T* d_features, T* d_p) const;

  int dims_;
  HashGridConfig config_;
  std::vector<Level> levels_;
  std::vector<T> params_, grads_;
  std::unique_ptr<TouchMarks> touched_;  // of grads_
};

extern template class PositionalEncoding<float>;
extern template class PositionalEncoding<double>;
extern template class HashGridEncoding<float>;
extern template class HashGridEncoding<double>;

}  // namespace p2n
