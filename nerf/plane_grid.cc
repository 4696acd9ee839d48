#include "nerf/plane_grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#ifdef __FMA__
#include <immintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <type_traits>

#include "base/declared_fields.h"
#include "nerf/denormals.h"

namespace p2n {
namespace {

constexpr Eigen::Index kBlock = 16384;                      // points per task of Forward() and InputGradient()
constexpr int kPlaneAxes[3][2] = {{0, 1}, {0, 2}, {1, 2}};  // xy, xz, yz

}  // namespace

nlohmann::json PlaneGridConfig::ToJson() const {
  nlohmann::json json = FieldsToJson(*this);
  json["otype"] = "Planes";
  return json;
}

void PlaneGridConfig::Check() const {
  CheckField(*this, levels, levels >= 1 && levels <= 8, "must be 1..8");
  CheckField(*this, features_per_level, features_per_level >= 1 && features_per_level <= 16, "must be 1..16");
  for (const int* resolution : {&finest_resolution, &depth_resolution}) {
    CheckField(*this, *resolution, *resolution >= (1 << (levels - 1)) && *resolution <= 8192,
               "must be 2^(levels - 1)..8192");
  }
}

PlaneGridConfig PlaneGridConfig::FromJson(const nlohmann::json& json) {
  PlaneGridConfig config;
  ReadFields(json, &config, {"otype"}, "planes config");
  return config;
}

template <typename T>
PlaneGridEncoding<T>::PlaneGridEncoding(const PlaneGridConfig& config, uint64_t seed) : config_(config) {
  config.Check();
  uint64_t offset = 0;
  for (int l = 0; l < config.levels; ++l) {
    const int halvings = config.levels - 1 - l;
    const uint32_t cells[3] = {static_cast<uint32_t>(config.finest_resolution >> halvings),
                               static_cast<uint32_t>(config.finest_resolution >> halvings),
                               static_cast<uint32_t>(config.depth_resolution >> halvings)};
    for (const auto& axes : kPlaneAxes) {
      Plane plane{{axes[0], axes[1]}, {cells[axes[0]], cells[axes[1]]}, static_cast<uint32_t>(offset)};
      planes_.push_back(plane);
      offset += uint64_t{plane.cells[0] + 1} * (plane.cells[1] + 1);
    }
  }
  const size_t values = offset * config.features_per_level;
  if (values > (size_t{1} << 28))
    throw std::invalid_argument("planes: more than 2^28 parameters " + config.ToJson().dump());
  // As K-planes: features uniform in [0.1, 0.5], so that every level's product starts small, positive and varied.
  params_.resize(values);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(0.1, 0.5);
  for (T& value : params_) value = static_cast<T>(uniform(random));
  grads_.assign(values, T(0));
  touched_ = std::make_unique<TouchMarks>(offset);
}

template <typename T>
typename PlaneGridEncoding<T>::Lookup PlaneGridEncoding<T>::CellLookup(const Plane& plane, uint32_t cell_u,
                                                                       uint32_t cell_v, T fu, T fv) {
  const uint32_t row = plane.cells[0] + 1;
  const uint32_t first = plane.offset + cell_v * row + cell_u;
  Lookup lookup;
  lookup.entries[0] = first;
  lookup.entries[1] = first + 1;
  lookup.entries[2] = first + row;
  lookup.entries[3] = first + row + 1;
  lookup.weights[0] = (T(1) - fu) * (T(1) - fv);
  lookup.weights[1] = fu * (T(1) - fv);
  lookup.weights[2] = (T(1) - fu) * fv;
  lookup.weights[3] = fu * fv;
  lookup.fraction[0] = fu;
  lookup.fraction[1] = fv;
  return lookup;
}

template <typename T>
typename PlaneGridEncoding<T>::Lookup PlaneGridEncoding<T>::Locate(const Plane& plane, const T* p) const {
  uint32_t cell[2];
  T fraction[2];
  for (int k = 0; k < 2; ++k) {
    // Into [0, 1] (a NaN coordinate to 0: std::max returns its first argument unless the second is greater); the
    // far edge stays in the last cell.
    const T position = std::min(std::max(T(0), p[plane.axis[k]]), T(1)) * static_cast<T>(plane.cells[k]);
    cell[k] = std::min(static_cast<uint32_t>(position), plane.cells[k] - 1);
    fraction[k] = position - static_cast<T>(cell[k]);
  }
  return CellLookup(plane, cell[0], cell[1], fraction[0], fraction[1]);
}

template <typename T>
void PlaneGridEncoding<T>::ReadLevel(int level, const T* p, Lookup* lookups, T* features) const {
  const int n = config_.features_per_level;
  for (int k = 0; k < 3; ++k) {
    lookups[k] = Locate(planes_[3 * level + k], p);
    Blend<0>(params_.data(), n, lookups[k], features + k * n);
  }
}

template <typename T>
void PlaneGridEncoding<T>::LocateGroup(int level, const Matrix& input, Eigen::Index first, int count,
                                       Lookup (*lookups)[kGroup], int only) const {
  // As Locate(), but each axis's cells and fractions in loops over the points without branches, which vectorise.
  uint32_t cell[3][kGroup];
  T fraction[3][kGroup];
  for (int d = 0; d < 3; ++d) {
    // Axis d's cells: the xy plane's along x and y, the xz plane's along z.
    const T cells = static_cast<T>(d < 2 ? planes_[3 * level].cells[d] : planes_[3 * level + 1].cells[1]);
    const int32_t last = static_cast<int32_t>(cells) - 1;
    const T* p = input.data() + first * 3 + d;
    T position[kGroup];
    for (int i = 0; i < count; ++i) position[i] = p[3 * i];
    for (int i = 0; i < count; ++i) position[i] = std::max(T(0), position[i]);
    for (int i = 0; i < count; ++i) position[i] = std::min(position[i], T(1)) * cells;
    for (int i = 0; i < count; ++i) {
      const int32_t c = std::min(static_cast<int32_t>(position[i]), last);
      cell[d][i] = static_cast<uint32_t>(c);
      fraction[d][i] = position[i] - static_cast<T>(c);
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (only >= 0 && k != only) continue;
    const Plane& plane = planes_[3 * level + k];
    const int u = plane.axis[0], v = plane.axis[1];
    for (int i = 0; i < count; ++i) {
      lookups[k][i] = CellLookup(plane, cell[u][i], cell[v][i], fraction[u][i], fraction[v][i]);
    }
  }
}

template <typename T>
void PlaneGridEncoding<T>::Prefetch(const Lookup (*lookups)[kGroup], int i, int features, const T* table, bool write) {
  for (int k = 0; k < 3; ++k) {
    // A cell's two lower and two upper vertices are side by side: one request for each pair.
    for (const int c : {0, 2}) {
      const T* address = table + size_t{lookups[k][i].entries[c]} * features;
      if (write) {
        __builtin_prefetch(address, 1);
      } else {
        __builtin_prefetch(address, 0);
      }
    }
  }
}

template <typename T>
template <int kFeatures>
void PlaneGridEncoding<T>::Blend(const T* table, int features, const Lookup& lookup, T* out) {
#ifdef __FMA__
  if constexpr (std::is_same_v<T, float> && kFeatures == 8) {
    __m256 sum =
        _mm256_mul_ps(_mm256_set1_ps(lookup.weights[0]), _mm256_loadu_ps(table + size_t{lookup.entries[0]} * 8));
    for (int c = 1; c < 4; ++c) {
      sum = _mm256_fmadd_ps(_mm256_set1_ps(lookup.weights[c]), _mm256_loadu_ps(table + size_t{lookup.entries[c]} * 8),
                            sum);
    }
    _mm256_storeu_ps(out, sum);
    return;
  }
#endif
  const int n = kFeatures > 0 ? kFeatures : features;
  std::fill_n(out, n, T(0));
  for (int c = 0; c < 4; ++c) {
    const T* entry = table + size_t{lookup.entries[c]} * n;
    for (int f = 0; f < n; ++f) out[f] += lookup.weights[c] * entry[f];
  }
}

template <typename T>
template <int kFeatures>
void PlaneGridEncoding<T>::Scatter(const T* d_features, int features, const Lookup& lookup, T* grads) {
#ifdef __FMA__
  if constexpr (std::is_same_v<T, float> && kFeatures == 8) {
    const __m256 d = _mm256_loadu_ps(d_features);
    for (int c = 0; c < 4; ++c) {
      float* grad = grads + size_t{lookup.entries[c]} * 8;
      _mm256_storeu_ps(grad, _mm256_fmadd_ps(_mm256_set1_ps(lookup.weights[c]), d, _mm256_loadu_ps(grad)));
    }
    return;
  }
#endif
  const int n = kFeatures > 0 ? kFeatures : features;
  for (int c = 0; c < 4; ++c) {
    T* grad = grads + size_t{lookup.entries[c]} * n;
    for (int f = 0; f < n; ++f) grad[f] += lookup.weights[c] * d_features[f];
  }
}

template <typename T>
template <int kFeatures, class Visit>
void PlaneGridEncoding<T>::VisitLevel(int level, const Matrix& input, Eigen::Index begin, Eigen::Index end,
                                      Visit&& visit) const {
  const int n = kFeatures > 0 ? kFeatures : config_.features_per_level;
  const T* table = params_.data();
  Lookup lookups[3][kGroup];
  T features[3 * kMaxFeatures];
  for (Eigen::Index group = begin; group < end; group += kGroup) {
    const int count = static_cast<int>(std::min<Eigen::Index>(kGroup, end - group));
    LocateGroup(level, input, group, count, lookups);
    for (int i = 0; i < count; ++i) {
      if (i + kPrefetchAhead < count) Prefetch(lookups, i + kPrefetchAhead, n, table, false);
      for (int k = 0; k < 3; ++k) Blend<kFeatures>(table, n, lookups[k][i], features + k * n);
      visit(group + i, static_cast<const T*>(features));
    }
  }
}

template <typename T>
void PlaneGridEncoding<T>::ProductGradient(const T* d_out, const T* features, int plane, int n, T* d_plane) {
  // d(f_0 f_1 f_2)/d(f_k): the product of the other two planes' features.
  const T* other0 = features + ((plane + 1) % 3) * n;
  const T* other1 = features + ((plane + 2) % 3) * n;
  for (int f = 0; f < n; ++f) d_plane[f] = d_out[f] * other0[f] * other1[f];
}

template <typename T>
template <int kFeatures>
void PlaneGridEncoding<T>::ForwardLevel(int level, const Matrix& input, Eigen::Index begin, Eigen::Index end,
                                        Matrix* output) const {
  const int n = kFeatures > 0 ? kFeatures : config_.features_per_level;
  VisitLevel<kFeatures>(level, input, begin, end, [&](Eigen::Index i, const T* features) {
    T* out = output->col(i).data() + level * n;
    for (int f = 0; f < n; ++f) out[f] = features[f] * features[n + f] * features[2 * n + f];
  });
}

template <typename T>
void PlaneGridEncoding<T>::Forward(const Matrix& input, Matrix* output) const {
  // Level by level in blocks of points, as the hash grid: a task reads one level's planes.
  const Eigen::Index n = input.cols(), blocks = (n + kBlock - 1) / kBlock;
  output->resize(output_dims(), n);
  tbb::parallel_for(Eigen::Index{0}, config_.levels * blocks, [&](Eigen::Index task) {
    FlushDenormalsOnThisThread();
    const int l = static_cast<int>(task / blocks);
    const Eigen::Index begin = task % blocks * kBlock, end = std::min(n, begin + kBlock);
    if (config_.features_per_level == 8) return ForwardLevel<8>(l, input, begin, end, output);
    ForwardLevel<0>(l, input, begin, end, output);
  });
}

template <typename T>
void PlaneGridEncoding<T>::ZeroGrad() {
  std::fill(grads_.begin(), grads_.end(), T(0));
  touched_->ClearAll();
}

template <typename T>
template <int kFeatures>
void PlaneGridEncoding<T>::PlaneGradients(int level, const Matrix& input, const Matrix& d_output, Eigen::Index begin,
                                          Eigen::Index end, T* d_planes) const {
  const int n = kFeatures > 0 ? kFeatures : config_.features_per_level;
  const size_t points = input.cols();
  VisitLevel<kFeatures>(level, input, begin, end, [&](Eigen::Index i, const T* features) {
    for (int k = 0; k < 3; ++k) {
      ProductGradient(d_output.col(i).data() + level * n, features, k, n,
                      d_planes + ((3 * level + k) * points + i) * n);
    }
  });
}

template <typename T>
template <int kFeatures>
void PlaneGridEncoding<T>::ScatterPlane(int plane, const Matrix& input, const T* d_planes) {
  const int n = kFeatures > 0 ? kFeatures : config_.features_per_level;
  const T* d_plane = d_planes + size_t(plane) * input.cols() * n;
  Lookup all_lookups[3][kGroup];
  const Lookup* lookups = all_lookups[plane % 3];
  for (Eigen::Index group = 0; group < input.cols(); group += kGroup) {
    const int count = static_cast<int>(std::min<Eigen::Index>(kGroup, input.cols() - group));
    LocateGroup(plane / 3, input, group, count, all_lookups, plane % 3);
    for (int i = 0; i < count; ++i) {
      if (i + kPrefetchAhead < count) {
        for (const int c : {0, 2})
          __builtin_prefetch(grads_.data() + size_t{lookups[i + kPrefetchAhead].entries[c]} * n, 1);
      }
      for (int c = 0; c < 4; ++c) touched_->Mark(lookups[i].entries[c]);
      Scatter<kFeatures>(d_plane + (group + i) * n, n, lookups[i], grads_.data());
    }
  }
}

template <typename T>
void PlaneGridEncoding<T>::Backward(const Matrix& input, const Matrix& d_output) {
  // First each point's gradient with respect to each plane's features (reading the planes as Forward() does),
  // then a task per plane adds them into its entries: no two tasks write one entry, and the levels' three planes
  // give the two cores a dozen tasks of about equal size.
  const Eigen::Index n = input.cols(), blocks = (n + kBlock - 1) / kBlock;
  const bool eight = config_.features_per_level == 8;
  const std::unique_ptr<T[]> d_planes(new T[size_t(n) * 3 * output_dims()]);
  tbb::parallel_for(Eigen::Index{0}, config_.levels * blocks, [&](Eigen::Index task) {
    FlushDenormalsOnThisThread();
    const int l = static_cast<int>(task / blocks);
    const Eigen::Index begin = task % blocks * kBlock, end = std::min(n, begin + kBlock);
    if (eight) return PlaneGradients<8>(l, input, d_output, begin, end, d_planes.get());
    PlaneGradients<0>(l, input, d_output, begin, end, d_planes.get());
  });
  tbb::parallel_for(0, 3 * config_.levels, [&](int plane) {
    FlushDenormalsOnThisThread();
    if (eight) return ScatterPlane<8>(plane, input, d_planes.get());
    ScatterPlane<0>(plane, input, d_planes.get());
  });
}

template <typename T>
void PlaneGridEncoding<T>::AddInputGradient(const T* p, const T* d_features, T* d_p) const {
  const int n = config_.features_per_level;
  Lookup lookups[3];
  T features[3 * kMaxFeatures], d_plane[kMaxFeatures];
  for (int l = 0; l < config_.levels; ++l) {
    ReadLevel(l, p, lookups, features);
    for (int k = 0; k < 3; ++k) {
      const Plane& plane = planes_[3 * l + k];
      ProductGradient(d_features + l * n, features, k, n, d_plane);
      T d_weight[4] = {};  // dL/d(each corner's weight)
      for (int c = 0; c < 4; ++c) {
        const T* entry = params_.data() + size_t{lookups[k].entries[c]} * n;
        for (int f = 0; f < n; ++f) d_weight[c] += d_plane[f] * entry[f];
      }
      // The weights are bilinear in the fractions, which grow at `cells` per unit of the coordinate; a clamped
      // coordinate has no gradient.
      const T fu = lookups[k].fraction[0], fv = lookups[k].fraction[1];
      const T d_fraction[2] = {(T(1) - fv) * (d_weight[1] - d_weight[0]) + fv * (d_weight[3] - d_weight[2]),
                               (T(1) - fu) * (d_weight[2] - d_weight[0]) + fu * (d_weight[3] - d_weight[1])};
      for (int a = 0; a < 2; ++a) {
        const int axis = plane.axis[a];
        if (p[axis] > T(0) && p[axis] < T(1)) d_p[axis] += d_fraction[a] * static_cast<T>(plane.cells[a]);
      }
    }
  }
}

template <typename T>
void PlaneGridEncoding<T>::InputGradient(const Matrix& input, const Matrix& d_output, Matrix* d_input) const {
  d_input->setZero(3, input.cols());
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, input.cols(), kBlock),
                    [&](const tbb::blocked_range<Eigen::Index>& range) {
                      FlushDenormalsOnThisThread();
                      for (Eigen::Index i = range.begin(); i < range.end(); ++i) {
                        AddInputGradient(input.col(i).data(), d_output.col(i).data(), d_input->col(i).data());
                      }
                    });
}

template class PlaneGridEncoding<float>;
template class PlaneGridEncoding<double>;

}  // namespace p2n
