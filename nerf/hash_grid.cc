#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#ifdef __FMA__
#include <immintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <type_traits>

#include "base/declared_fields.h"
#include "nerf/denormals.h"
#include "nerf/encoding.h"

namespace p2n {
namespace {

constexpr uint32_t kPrimes[3] = {1u, 2654435761u, 805459861u};
constexpr Eigen::Index kBlock = 16384;  // points per task of Forward()
// Forward() and Backward() find the corners of a group of points before they read any of their entries, so that
// the reads are independent and many are in flight at once (a hashed level's table is larger than the core's
// cache), and ask the cache for a point's entries this many points before they read them. throughput_bench,
// random points, default layout: grouping took the forward pass from 1.5 to 2.7 M samples/s, prefetching 8 ahead
// to 4.6 (4 and 16 were slower), and backward from 1.5 to 5.1.
constexpr Eigen::Index kGroup = 64;
constexpr int kPrefetchAhead = 8;
#ifdef __FMA__
// A two-float entry in the low half of a register (one 8-byte load or store: GCC 12 leaves the two-feature loops
// scalar, as SLP vectorisation is off in this project). The 64-bit integer forms may alias any type.
__m128 LoadPair(const float* pair) { return _mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(pair))); }
void StorePair(float* pair, __m128 value) {
  _mm_storel_epi64(reinterpret_cast<__m128i*>(pair), _mm_castps_si128(value));
}
#endif
constexpr Eigen::Index kTransposeBlock = 256;  // points per task interleaving the levels' features (32 KB a side)

}  // namespace

nlohmann::json HashGridConfig::ToJson() const {
  nlohmann::json json = FieldsToJson(*this);
  json["otype"] = "HashGrid";
  return json;
}

void HashGridConfig::Check() const {
  CheckField(*this, levels, levels >= 1 && levels <= 64, "must be 1..64");
  CheckField(*this, features_per_level, features_per_level >= 1 && features_per_level <= 8, "must be 1..8");
  CheckField(*this, log2_table_size, log2_table_size >= 4 && log2_table_size <= 24, "must be 4..24");
  CheckField(*this, base_resolution, base_resolution >= 1, "must be at least 1");
  CheckField(*this, finest_resolution, finest_resolution >= base_resolution && finest_resolution <= (1 << 20),
             "must be base_resolution..2^20");
}

HashGridConfig HashGridConfig::FromJson(const nlohmann::json& json) {
  HashGridConfig config;
  ReadFields(json, &config, {"otype"}, "hash grid config");
  return config;
}

template <typename T>
HashGridEncoding<T>::HashGridEncoding(int dims, const HashGridConfig& config, uint64_t seed)
    : dims_(dims), config_(config) {
  if (dims < 1 || dims > 3) throw std::invalid_argument("hash grid: " + std::to_string(dims) + " dimensions");
  config.Check();
  const double growth =
      config.levels > 1
          ? std::exp((std::log(config.finest_resolution) - std::log(config.base_resolution)) / (config.levels - 1))
          : 1.0;
  const uint64_t max_size = uint64_t{1} << config.log2_table_size;
  uint64_t offset = 0;
  for (int l = 0; l < config.levels; ++l) {
    Level level;
    level.scale = config.base_resolution * std::pow(growth, l);
    level.vertices = static_cast<uint32_t>(std::ceil(level.scale)) + 2;
    const double dense_size = std::pow(static_cast<double>(level.vertices), dims);
    level.dense = dense_size <= static_cast<double>(max_size);
    level.size = static_cast<uint32_t>(level.dense ? dense_size : max_size);
    level.offset = static_cast<uint32_t>(offset);
    offset += level.size;
    levels_.push_back(level);
  }
  const size_t values = offset * config.features_per_level;
  if (values > (size_t{1} << 27))
    throw std::invalid_argument("hash grid: more than 2^27 parameters " + config.ToJson().dump());
  params_.resize(values);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1e-4, 1e-4);
  for (T& value : params_) value = static_cast<T>(uniform(random));
  grads_.assign(values, T(0));
  touched_ = std::make_unique<TouchMarks>(offset);
}

template <typename T>
nlohmann::json HashGridEncoding<T>::Config() const {
  nlohmann::json config = config_.ToJson();
  config["dims"] = dims_;
  return config;
}

template <typename T>
uint32_t HashGridEncoding<T>::EntryIndex(const Level& level, const uint32_t* vertex) const {
  uint32_t index = 0;
  if (level.dense) {
    uint32_t stride = 1;
    for (int d = 0; d < dims_; ++d) {
      index += vertex[d] * stride;
      stride *= level.vertices;
    }
  } else {
    for (int d = 0; d < dims_; ++d) index ^= vertex[d] * kPrimes[d];
    index &= level.size - 1;  // hashed levels have a power-of-two size
  }
  return level.offset + index;
}

template <typename T>
void HashGridEncoding<T>::Corners(const Level& level, const T* p, uint32_t* entries, T* weights) const {
  uint32_t base[3];
  T fraction[3];
  for (int d = 0; d < dims_; ++d) {
    // Into [0, 1] (a NaN coordinate to 0: std::max returns its first argument unless the second is greater).
    const T position = std::min(std::max(T(0), p[d]), T(1)) * static_cast<T>(level.scale);
    const T floor = std::floor(position);
    base[d] = static_cast<uint32_t>(floor);
    fraction[d] = position - floor;
  }
  for (int corner = 0; corner < (1 << dims_); ++corner) {
    uint32_t vertex[3];
    T weight = T(1);
    for (int d = 0; d < dims_; ++d) {
      const bool upper = (corner >> d) & 1;
      vertex[d] = base[d] + upper;
      weight *= upper ? fraction[d] : T(1) - fraction[d];
    }
    entries[corner] = EntryIndex(level, vertex);
    weights[corner] = weight;
  }
}

template <typename T>
void HashGridEncoding<T>::GroupCorners(const Level& level, const Matrix& input, Eigen::Index first, int count,
                                       uint32_t* entries, T* weights) const {
  if (dims_ != 3) {
    for (int i = 0; i < count; ++i) {
      uint32_t point_entries[8];
      T point_weights[8];
      Corners(level, input.col(first + i).data(), point_entries, point_weights);
      for (int corner = 0; corner < (1 << dims_); ++corner) {
        entries[corner * kGroup + i] = point_entries[corner];
        weights[corner * kGroup + i] = point_weights[corner];
      }
    }
    return;
  }
  // The common case, as Corners() and EntryIndex() but in loops over the points without branches, which
  // vectorise: first each point's cell and where in it the point lies, then the corners. In T, as the points:
  // float keeps a 2048-cell level's fractions to 2^-13 of a cell, and twice the lanes of double (fox's render:
  // these loops 9.2 -> 7.8% of the time).
  uint32_t base[3][kGroup];
  T fraction[3][kGroup];
  T coordinate[kGroup];
  const T scale = static_cast<T>(level.scale);
  for (int d = 0; d < 3; ++d) {
    const T* p = input.data() + first * 3 + d;
    // As in Corners(): clamped to [0, 1]. (Clamping in the loop that reads the points, with std::clamp, or to both
    // bounds in one loop keeps GCC 12 from vectorising these loops without AVX-512.)
    for (int i = 0; i < count; ++i) coordinate[i] = p[3 * i];
    for (int i = 0; i < count; ++i) coordinate[i] = std::max(T(0), coordinate[i]);
    for (int i = 0; i < count; ++i) coordinate[i] = std::min(coordinate[i], T(1));
    for (int i = 0; i < count; ++i) {
      // The position is at least 0, so truncation is its floor.
      const T position = coordinate[i] * scale;
      const int32_t cell = static_cast<int32_t>(position);
      base[d][i] = static_cast<uint32_t>(cell);
      fraction[d][i] = position - static_cast<T>(cell);
    }
  }
  const uint32_t stride = level.dense ? level.vertices : kPrimes[1];
  const uint32_t stride2 = level.dense ? level.vertices * level.vertices : kPrimes[2];
  const uint32_t mask = level.dense ? ~0u : level.size - 1;
  for (int corner = 0; corner < 8; ++corner) {
    const uint32_t dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
    for (int i = 0; i < count; ++i) {
      const uint32_t x = base[0][i] + dx, y = (base[1][i] + dy) * stride, z = (base[2][i] + dz) * stride2;
      entries[corner * kGroup + i] = level.offset + (level.dense ? x + y + z : (x ^ y ^ z) & mask);
      weights[corner * kGroup + i] = (dx ? fraction[0][i] : T(1) - fraction[0][i]) *
                                     (dy ? fraction[1][i] : T(1) - fraction[1][i]) *
                                     (dz ? fraction[2][i] : T(1) - fraction[2][i]);
    }
  }
}

template <typename T>
void HashGridEncoding<T>::PrefetchEntries(const uint32_t* entries, int corners, int features, const T* table,
                                          bool write) const {
  for (int c = 0; c < corners; ++c) {
    const T* address = table + size_t{entries[c * kGroup]} * features;
    if (write) {
      __builtin_prefetch(address, 1);
    } else {
      __builtin_prefetch(address, 0);
    }
  }
}

template <typename T>
typename HashGridEncoding<T>::LevelLayout HashGridEncoding<T>::Layout() const {
  if (dims_ != 3) return kOther;
  return config_.features_per_level == 2 ? kCube2 : config_.features_per_level == 4 ? kCube4 : kOther;
}

template <typename T>
template <int kFeatures, int kCorners>
void HashGridEncoding<T>::ForwardLevel(int l, const Matrix& input, Eigen::Index begin, Eigen::Index end,
                                       T* by_level) const {
  const int features = kFeatures > 0 ? kFeatures : config_.features_per_level;
  const int corners = kCorners > 0 ? kCorners : 1 << dims_;
  const T* table = params_.data();
  T* out = by_level + size_t(input.cols()) * l * features;
  uint32_t entries[kGroup * 8];
  T weights[kGroup * 8];
  for (Eigen::Index group = begin; group < end; group += kGroup) {
    const int count = static_cast<int>(std::min(kGroup, end - group));
    GroupCorners(levels_[l], input, group, count, entries, weights);
    for (int i = 0; i < count; ++i) {
      if (i + kPrefetchAhead < count) PrefetchEntries(entries + i + kPrefetchAhead, corners, features, table, false);
#ifdef __FMA__
      if constexpr (std::is_same_v<T, float> && kFeatures == 2) {
        __m128 sum = _mm_setzero_ps();
        for (int c = 0; c < corners; ++c) {
          sum = _mm_fmadd_ps(_mm_set1_ps(weights[c * kGroup + i]),
                             LoadPair(table + size_t{entries[c * kGroup + i]} * 2), sum);
        }
        StorePair(out + (group + i) * 2, sum);
        continue;
      }
#endif
      T sum[8] = {};
      for (int c = 0; c < corners; ++c) {
        const T* feature = table + size_t{entries[c * kGroup + i]} * features;
        for (int f = 0; f < features; ++f) sum[f] += weights[c * kGroup + i] * feature[f];
      }
      std::copy(sum, sum + features, out + (group + i) * features);
    }
  }
}

template <typename T>
void HashGridEncoding<T>::Forward(const Matrix& input, Matrix* output) const {
  // Level by level, in blocks of points: a task reads one level's table (a few MB at most), which stays in the
  // cache for its whole block; reading every level for each point would cycle through all the tables. Each level
  // writes its features for consecutive points side by side (level-major), which a second pass interleaves into
  // the points' columns: written straight into the columns, each level's task touched a cache line of every
  // point's column for a few bytes. 65,536 random points, default layout, alternated three times: forward 2.5 ->
  // 3.1 M samples/s, and Backward() (which reads the gradient the same way) 1.5 -> 2.3.
  const Eigen::Index n = input.cols();
  const std::unique_ptr<T[]> by_level(new T[size_t(n) * output_dims()]);
  const Eigen::Index blocks = (n + kBlock - 1) / kBlock;
  tbb::parallel_for(Eigen::Index{0}, config_.levels * blocks, [&](Eigen::Index task) {
    FlushDenormalsOnThisThread();
    const int l = static_cast<int>(task / blocks);
    const Eigen::Index begin = task % blocks * kBlock, end = std::min(n, begin + kBlock);
    switch (Layout()) {
      case kCube2:
        return ForwardLevel<2, 8>(l, input, begin, end, by_level.get());
      case kCube4:
        return ForwardLevel<4, 8>(l, input, begin, end, by_level.get());
      default:
        return ForwardLevel<0, 0>(l, input, begin, end, by_level.get());
    }
  });
  output->resize(output_dims(), n);  // every value is written
  Transpose(by_level.get(), n, output->data(), true);
}

template <typename T>
template <int kFeatures>
void HashGridEncoding<T>::TransposeBlock(const T* from, Eigen::Index n, Eigen::Index begin, Eigen::Index end, T* to,
                                         bool to_points) const {
  const int features = kFeatures > 0 ? kFeatures : config_.features_per_level, rows = output_dims();
  for (int l = 0; l < config_.levels; ++l) {
    for (Eigen::Index i = begin; i < end; ++i) {
      const size_t level_major = (size_t(n) * l + i) * features, point_major = i * rows + l * features;
      for (int f = 0; f < features; ++f) {
        if (to_points) {
          to[point_major + f] = from[level_major + f];
        } else {
          to[level_major + f] = from[point_major + f];
        }
      }
    }
  }
}

template <typename T>
void HashGridEncoding<T>::Transpose(const T* from, Eigen::Index n, T* to, bool to_points) const {
  tbb::parallel_for(Eigen::Index{0}, (n + kTransposeBlock - 1) / kTransposeBlock, [&](Eigen::Index block) {
    const Eigen::Index begin = block * kTransposeBlock, end = std::min(n, begin + kTransposeBlock);
    switch (Layout()) {
      case kCube2:
        return TransposeBlock<2>(from, n, begin, end, to, to_points);
      case kCube4:
        return TransposeBlock<4>(from, n, begin, end, to, to_points);
      default:
        return TransposeBlock<0>(from, n, begin, end, to, to_points);
    }
  });
}

template <typename T>
void HashGridEncoding<T>::ZeroGrad() {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grads_.size(), size_t{1} << 16),
                    [&](const tbb::blocked_range<size_t>& range) {
                      std::fill(grads_.begin() + range.begin(), grads_.begin() + range.end(), T(0));
                    });
  touched_->ClearAll();
}

template <typename T>
template <int kFeatures, int kCorners>
void HashGridEncoding<T>::BackwardLevel(int l, const Matrix& input, const T* d_by_level) {
  const int features = kFeatures > 0 ? kFeatures : config_.features_per_level;
  const int corners = kCorners > 0 ? kCorners : 1 << dims_;
  T* grads = grads_.data();
  const T* d_in = d_by_level + size_t(input.cols()) * l * features;
  uint32_t entries[kGroup * 8];
  T weights[kGroup * 8];
  for (Eigen::Index group = 0; group < input.cols(); group += kGroup) {
    const int count = static_cast<int>(std::min(kGroup, input.cols() - group));
    GroupCorners(levels_[l], input, group, count, entries, weights);
    for (int i = 0; i < count; ++i) {
      if (i + kPrefetchAhead < count) PrefetchEntries(entries + i + kPrefetchAhead, corners, features, grads, true);
#ifdef __FMA__
      if constexpr (std::is_same_v<T, float> && kFeatures == 2) {
        const __m128 d_out = LoadPair(d_in + (group + i) * 2);
        for (int c = 0; c < corners; ++c) {
          const uint32_t entry = entries[c * kGroup + i];
          touched_->Mark(entry);
          float* grad = grads + size_t{entry} * 2;
          StorePair(grad, _mm_fmadd_ps(_mm_set1_ps(weights[c * kGroup + i]), d_out, LoadPair(grad)));
        }
        continue;
      }
#endif
      T d_out[8];
      std::copy_n(d_in + (group + i) * features, features, d_out);
      for (int c = 0; c < corners; ++c) {
        const uint32_t entry = entries[c * kGroup + i];
        touched_->Mark(entry);
        T* grad = grads + size_t{entry} * features;
        for (int f = 0; f < features; ++f) grad[f] += weights[c * kGroup + i] * d_out[f];
      }
    }
  }
}

template <typename T>
void HashGridEncoding<T>::Backward(const Matrix& input, const Matrix& d_output) {
  // The gradient level-major first, as Forward() writes it: each level's task then reads its own contiguous part.
  const std::unique_ptr<T[]> d_by_level(new T[d_output.size()]);
  Transpose(d_output.data(), input.cols(), d_by_level.get(), false);
  tbb::parallel_for(0, config_.levels, [&](int l) {
    FlushDenormalsOnThisThread();
    switch (Layout()) {
      case kCube2:
        return BackwardLevel<2, 8>(l, input, d_by_level.get());
      case kCube4:
        return BackwardLevel<4, 8>(l, input, d_by_level.get());
      default:
        return BackwardLevel<0, 0>(l, input, d_by_level.get());
    }
  });
}

template <typename T>
void HashGridEncoding<T>::InputGradient(const Matrix& input, const Matrix& d_output, Matrix* d_input) const {
  const int features = config_.features_per_level;
  // Blocks of points as tasks, every level in turn within one (as Forward() reads the tables): a point's column
  // is written by one task, its levels added in order.
  const Eigen::Index n = input.cols();
  d_input->setZero(dims_, n);
  tbb::parallel_for(Eigen::Index{0}, (n + kBlock - 1) / kBlock, [&](Eigen::Index block) {
    FlushDenormalsOnThisThread();
    const Eigen::Index begin = block * kBlock, end = std::min(n, begin + kBlock);
    for (int l = 0; l < config_.levels; ++l) {
      for (Eigen::Index i = begin; i < end; ++i) {
        AddInputGradient(levels_[l], input.col(i).data(), d_output.col(i).data() + l * features,
                         d_input->col(i).data());
      }
    }
  });
}

template <typename T>
void HashGridEncoding<T>::AddInputGradient(const Level& level, const T* p, const T* d_features, T* d_p) const {
  T fraction[3];
  bool inside[3];  // a clamped coordinate has no gradient
  for (int d = 0; d < dims_; ++d) {
    const T position = std::clamp(p[d], T(0), T(1)) * static_cast<T>(level.scale);
    fraction[d] = position - std::floor(position);
    inside[d] = p[d] > T(0) && p[d] < T(1);
  }
  const int features = config_.features_per_level;
  uint32_t entries[8];
  T weights[8];
  Corners(level, p, entries, weights);
  for (int corner = 0; corner < (1 << dims_); ++corner) {
    const T* feature = params_.data() + size_t{entries[corner]} * features;
    T d_weight = T(0);  // dL/d(this corner's weight)
    for (int f = 0; f < features; ++f) d_weight += d_features[f] * feature[f];
    for (int d = 0; d < dims_; ++d) {
      if (!inside[d]) continue;
      // The weight is a product over axes of fraction or 1 - fraction; fraction grows at `scale` per unit of p.
      T slope = static_cast<T>(level.scale);
      for (int e = 0; e < dims_; ++e) {
        if (e != d) slope *= ((corner >> e) & 1) ? fraction[e] : T(1) - fraction[e];
      }
      d_p[d] += ((corner >> d) & 1) ? d_weight * slope : -d_weight * slope;
    }
  }
}

template class HashGridEncoding<float>;
template class HashGridEncoding<double>;

}  // namespace p2n
