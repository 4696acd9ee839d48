#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "nerf/denormals.h"
#include "nerf/encoding.h"

namespace p2n {
namespace {

constexpr uint32_t kPrimes[3] = {1u, 2654435761u, 805459861u};
constexpr Eigen::Index kBlock = 16384;  // points per task of Forward()
// A hashed level's entries are scattered over a table larger than the cache: Forward() asks for the entries of
// the point this far ahead while it works on the current one, so that several points' reads are in flight
// (throughput_bench: +8%; the same in Backward() gained nothing).
constexpr Eigen::Index kPrefetchAhead = 4;

}  // namespace

nlohmann::json HashGridConfig::ToJson() const {
  return {{"otype", "HashGrid"},
          {"levels", levels},
          {"features_per_level", features_per_level},
          {"log2_table_size", log2_table_size},
          {"base_resolution", base_resolution},
          {"finest_resolution", finest_resolution}};
}

HashGridConfig HashGridConfig::FromJson(const nlohmann::json& json) {
  HashGridConfig config;
  config.levels = json.value("levels", config.levels);
  config.features_per_level = json.value("features_per_level", config.features_per_level);
  config.log2_table_size = json.value("log2_table_size", config.log2_table_size);
  config.base_resolution = json.value("base_resolution", config.base_resolution);
  config.finest_resolution = json.value("finest_resolution", config.finest_resolution);
  return config;
}

template <typename T>
HashGridEncoding<T>::HashGridEncoding(int dims, const HashGridConfig& config, uint64_t seed)
    : dims_(dims), config_(config) {
  if (dims < 1 || dims > 3 || config.levels < 1 || config.levels > 64 || config.features_per_level < 1 ||
      config.features_per_level > 8 || config.log2_table_size < 4 || config.log2_table_size > 24 ||
      config.base_resolution < 1 || config.finest_resolution < config.base_resolution ||
      config.finest_resolution > (1 << 20)) {
    throw std::invalid_argument("hash grid: invalid config " + config.ToJson().dump());
  }
  const double growth = config.levels > 1 ? std::exp((std::log(config.finest_resolution) -
                                                      std::log(config.base_resolution)) / (config.levels - 1))
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
  if (values > (size_t{1} << 27)) throw std::invalid_argument("hash grid: more than 2^27 parameters " + config.ToJson().dump());
  params_.resize(values);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1e-4, 1e-4);
  for (T& value : params_) value = static_cast<T>(uniform(random));
  grads_.assign(values, T(0));
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
template <class Visit>
void HashGridEncoding<T>::ForEachCorner(const Level& level, const T* p, Visit visit) const {
  uint32_t base[3];
  T fraction[3];
  for (int d = 0; d < dims_; ++d) {
    const double position = std::clamp(static_cast<double>(p[d]), 0.0, 1.0) * level.scale;
    const double floor = std::floor(position);
    base[d] = static_cast<uint32_t>(floor);
    fraction[d] = static_cast<T>(position - floor);
  }
  if (dims_ == 3) {
    // The common case, unrolled: the 8 entries are computed before any is read, so the loads overlap.
    uint32_t entries[8];
    T weights[8];
    for (int corner = 0; corner < 8; ++corner) {
      const uint32_t x = base[0] + (corner & 1), y = base[1] + ((corner >> 1) & 1), z = base[2] + (corner >> 2);
      entries[corner] = level.offset + (level.dense ? x + level.vertices * (y + level.vertices * z)
                                                    : (x ^ y * kPrimes[1] ^ z * kPrimes[2]) & (level.size - 1));
      weights[corner] = ((corner & 1) ? fraction[0] : T(1) - fraction[0]) *
                        ((corner & 2) ? fraction[1] : T(1) - fraction[1]) *
                        ((corner & 4) ? fraction[2] : T(1) - fraction[2]);
    }
    for (int corner = 0; corner < 8; ++corner) visit(entries[corner], weights[corner]);
    return;
  }
  for (int corner = 0; corner < (1 << dims_); ++corner) {
    uint32_t vertex[3];
    T weight = T(1);
    for (int d = 0; d < dims_; ++d) {
      const bool upper = (corner >> d) & 1;
      vertex[d] = base[d] + upper;
      weight *= upper ? fraction[d] : T(1) - fraction[d];
    }
    visit(EntryIndex(level, vertex), weight);
  }
}

template <typename T>
void HashGridEncoding<T>::Prefetch(const Level& level, const T* p) const {
  if (level.dense) return;  // small enough to stay in the cache
  ForEachCorner(level, p, [&](uint32_t entry, T) {
    __builtin_prefetch(params_.data() + size_t{entry} * config_.features_per_level);
  });
}

template <typename T>
void HashGridEncoding<T>::Forward(const Matrix& input, Matrix* output) const {
  // Level by level, in blocks of points: a task reads one level's table (a few MB at most), which stays in the
  // cache for its whole block; reading every level for each point would cycle through all the tables.
  const Eigen::Index n = input.cols();
  const int features = config_.features_per_level;
  output->setZero(output_dims(), n);
  const Eigen::Index blocks = (n + kBlock - 1) / kBlock;
  tbb::parallel_for(Eigen::Index{0}, config_.levels * blocks, [&](Eigen::Index task) {
    FlushDenormalsOnThisThread();
    const int l = static_cast<int>(task / blocks);
    const Eigen::Index begin = task % blocks * kBlock, end = std::min(n, begin + kBlock);
    for (Eigen::Index i = begin; i < end; ++i) {
      if (i + kPrefetchAhead < end) Prefetch(levels_[l], input.col(i + kPrefetchAhead).data());
      T* out = output->col(i).data() + l * features;
      ForEachCorner(levels_[l], input.col(i).data(), [&](uint32_t entry, T weight) {
        const T* feature = params_.data() + size_t{entry} * features;
        for (int f = 0; f < features; ++f) out[f] += weight * feature[f];
      });
    }
  });
}

template <typename T>
void HashGridEncoding<T>::ZeroGrad() {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, grads_.size(), size_t{1} << 16), [&](const tbb::blocked_range<size_t>& range) {
    std::fill(grads_.begin() + range.begin(), grads_.begin() + range.end(), T(0));
  });
}

template <typename T>
void HashGridEncoding<T>::Backward(const Matrix& input, const Matrix& d_output) {
  const int features = config_.features_per_level;
  tbb::parallel_for(0, config_.levels, [&](int l) {
    FlushDenormalsOnThisThread();
    for (Eigen::Index i = 0; i < input.cols(); ++i) {
      const T* d_out = d_output.col(i).data() + l * features;
      ForEachCorner(levels_[l], input.col(i).data(), [&](uint32_t entry, T weight) {
        T* grad = grads_.data() + size_t{entry} * features;
        for (int f = 0; f < features; ++f) grad[f] += weight * d_out[f];
      });
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
    const double position = std::clamp(static_cast<double>(p[d]), 0.0, 1.0) * level.scale;
    fraction[d] = static_cast<T>(position - std::floor(position));
    inside[d] = p[d] > T(0) && p[d] < T(1);
  }
  const int features = config_.features_per_level;
  int corner = 0;
  ForEachCorner(level, p, [&](uint32_t entry, T) {
    const T* feature = params_.data() + size_t{entry} * features;
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
    ++corner;
  });
}

template class HashGridEncoding<float>;
template class HashGridEncoding<double>;

}  // namespace p2n
