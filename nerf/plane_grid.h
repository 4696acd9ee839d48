#pragma once
// A factorised encoding of 3D points (K-planes' planes, Fridovich-Keil et al. 2023): at each level three dense,
// axis-aligned feature planes (xy, xz, yz), each read by bilinear interpolation; a point's features at a level
// are the element-wise product of its three planes' features, which locates them in 3D as a rank-one tensor
// would. Levels double in resolution up to the finest. Dense planes read neighbouring memory for neighbouring
// points, where a hash grid's finer levels collide and scatter; in a forward-facing scene's normalised device
// coordinates the xy plane is the image plane, which is given its own resolution.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <vector>

#include "nerf/encoding.h"
#include "nerf/touch_marks.h"

namespace p2n {

struct PlaneGridConfig {
  static constexpr const char* kName = "planes";  // checks name planes.FIELD
  int levels = 4;                                 // resolutions, halving from the finest
  int features_per_level = 8;                     // of each plane, and of the product a level gives
  int finest_resolution = 512;                    // cells along x and y at the finest level
  int depth_resolution = 512;                     // cells along z at the finest level

  template <class V>
  void Visit(V& v) {
    v("levels", levels);
    v("features_per_level", features_per_level);
    v("finest_resolution", finest_resolution);
    v("depth_resolution", depth_resolution);
  }

  // std::invalid_argument naming the field and its rule.
  void Check() const;
  nlohmann::json ToJson() const;
  // The inverse of ToJson(); missing keys keep their defaults; std::invalid_argument for an unknown key or a
  // value of the wrong type.
  static PlaneGridConfig FromJson(const nlohmann::json& json);
  bool operator==(const PlaneGridConfig& other) const = default;
};

template <typename T>
class PlaneGridEncoding : public Encoding<T> {
 public:
  using typename Encoding<T>::Matrix;
  PlaneGridEncoding(const PlaneGridConfig& config, uint64_t seed);

  int input_dims() const override { return 3; }
  int output_dims() const override { return config_.levels * config_.features_per_level; }
  nlohmann::json Config() const override { return config_.ToJson(); }
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
  static constexpr int kMaxFeatures = 16;
  struct Plane {
    int axis[2];          // the point's coordinates it reads (u, v)
    uint32_t cells[2];    // along u and v
    uint32_t offset = 0;  // its first entry (vertex), row-major in v then u
  };
  // Where point `p` falls on `plane`: its four vertices' entries (corner bit 0: upper along u, bit 1: along v),
  // their bilinear weights, and its fractions within the cell along u and v.
  struct Lookup {
    uint32_t entries[4];
    T weights[4];
    T fraction[2];
  };
  Lookup Locate(const Plane& plane, const T* p) const;
  // The lookup of the point at fractions (fu, fv) of cell (cell_u, cell_v).
  static Lookup CellLookup(const Plane& plane, uint32_t cell_u, uint32_t cell_v, T fu, T fv);
  // The three planes of `level` at point `p`: their lookups and features (features[k * F + f]).
  void ReadLevel(int level, const T* p, Lookup* lookups, T* features) const;
  // Forward() and Backward() locate a group of points on a level's three planes (lookups[plane][point]) before
  // they read any entry, and ask the cache for a point's entries kPrefetchAhead points ahead, as the hash grid does.
  static constexpr int kGroup = 64, kPrefetchAhead = 8;
  // `only` >= 0: that plane's lookups alone.
  void LocateGroup(int level, const Matrix& input, Eigen::Index first, int count, Lookup (*lookups)[kGroup],
                   int only = -1) const;
  static void Prefetch(const Lookup (*lookups)[kGroup], int i, int features, const T* table, bool write);
  // out = the located point's features (kFeatures of them, 0: `features`); Scatter() adds d_features times each
  // corner's weight into `grads`.
  template <int kFeatures>
  static void Blend(const T* table, int features, const Lookup& lookup, T* out);
  template <int kFeatures>
  static void Scatter(const T* d_features, int features, const Lookup& lookup, T* grads);
  // Calls visit(point, features) with the three planes' features (features[k * F + f]) at `level` of each point
  // begin..end, kFeatures features per level (0: any).
  template <int kFeatures, class Visit>
  void VisitLevel(int level, const Matrix& input, Eigen::Index begin, Eigen::Index end, Visit&& visit) const;
  // dL/d(plane k's features) given dL/d(the level's product of the three) and the three planes' features.
  static void ProductGradient(const T* d_out, const T* features, int plane, int n, T* d_plane);
  // Adds dL/d(p) given dL/d(p's features at every level), into d_p.
  void AddInputGradient(const T* p, const T* d_features, T* d_p) const;
  // Forward() of one level for points begin..end, kFeatures features per level (0: any).
  template <int kFeatures>
  void ForwardLevel(int level, const Matrix& input, Eigen::Index begin, Eigen::Index end, Matrix* output) const;
  // Backward()'s two passes: dL/d(each plane's features) of points begin..end at `level` into `d_planes` (plane
  // after plane, the points' features side by side), then those of plane `plane` added into its entries.
  template <int kFeatures>
  void PlaneGradients(int level, const Matrix& input, const Matrix& d_output, Eigen::Index begin, Eigen::Index end,
                      T* d_planes) const;
  template <int kFeatures>
  void ScatterPlane(int plane, const Matrix& input, const T* d_planes);

  PlaneGridConfig config_;
  std::vector<Plane> planes_;  // level l's at 3 l .. 3 l + 2: xy, xz, yz
  std::vector<T> params_, grads_;
  std::unique_ptr<TouchMarks> touched_;  // of grads_
};

extern template class PlaneGridEncoding<float>;
extern template class PlaneGridEncoding<double>;

}  // namespace p2n
