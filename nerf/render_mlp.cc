#include "nerf/render_mlp.h"

#if (defined(__AVX512BF16__) && defined(__AVX512BW__) && defined(__AVX512VL__)) || \
    (defined(__AVX2__) && defined(__FMA__))
#define P2N_RENDER_MLP 1
#include <immintrin.h>
#endif

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace p2n {
namespace {

#ifdef P2N_RENDER_MLP
constexpr Eigen::Index kBlockSamples = 192;  // samples taken through every layer at a time (in the cache)
#if defined(__AVX512BF16__) && defined(__AVX512BW__) && defined(__AVX512VL__)
// bfloat16 pairs: a 32-bit word holds two inputs' values, and vdpbf16ps adds both products to a float lane.
struct Kernel {
  static constexpr const char* kName = "AVX-512 BF16";
  static constexpr bool kRounds = true;
  using Acc = __m512;
  static constexpr int kLanes = 16, kPerWord = 2, kMaxRows = 4;
  // Samples of a tile of kRows row blocks: up to 24 accumulators in registers, and at least 12 (independent sums
  // to keep the multiply-add units busy through their latency).
  static constexpr int Samples(int rows) { return rows <= 2 ? 12 : 24 / rows; }
  static constexpr int kPadSamples = 24;  // a multiple of every tile's samples

  // bfloat16 of x, rounded to nearest even (as the instructions round).
  static uint16_t Value(float x) {
    uint32_t bits;
    std::memcpy(&bits, &x, 4);
    return static_cast<uint16_t>((bits + 0x7fff + ((bits >> 16) & 1)) >> 16);
  }
  static uint32_t Word(const float* values) { return Value(values[0]) | uint32_t{Value(values[1])} << 16; }
  using Weights = __m512bh;
  static Acc Load(const float* p) { return _mm512_loadu_ps(p); }
  static Weights LoadWeights(const uint32_t* p) { return (__m512bh)_mm512_loadu_si512(p); }
  static Acc MulAdd(Acc acc, Weights weights, uint32_t input) {
    return _mm512_dpbf16_ps(acc, weights, (__m512bh)_mm512_set1_epi32(static_cast<int32_t>(input)));
  }
  // ReLU of a block of rows, as the next layer's inputs (bfloat16, two to a word).
  static void StoreHidden(Acc acc, uint32_t* out) {
    const __m256bh packed = _mm512_cvtneps_pbh(_mm512_max_ps(acc, _mm512_setzero_ps()));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), (__m256i)packed);
  }
  static void StoreFirst(Acc acc, float* out, int count) {
    _mm512_mask_storeu_ps(out, static_cast<__mmask16>((1u << count) - 1), acc);
  }
};
#else
// float: a word holds one input's value, and a float multiply-add adds its product to each lane.
struct Kernel {
  static constexpr const char* kName = "AVX2";
  static constexpr bool kRounds = false;
  using Acc = __m256;
  static constexpr int kLanes = 8, kPerWord = 1, kMaxRows = 2;
  // Up to 12 accumulators besides the weights and the broadcast input, of AVX2's 16 registers.
  static constexpr int Samples(int rows) { return 12 / rows; }
  static constexpr int kPadSamples = 12;

  static uint32_t Word(const float* values) {
    uint32_t bits;
    std::memcpy(&bits, values, 4);
    return bits;
  }
  using Weights = __m256;
  static Acc Load(const float* p) { return _mm256_loadu_ps(p); }
  static Weights LoadWeights(const uint32_t* p) { return _mm256_loadu_ps(reinterpret_cast<const float*>(p)); }
  static Acc MulAdd(Acc acc, Weights weights, uint32_t input) {
    float x;
    std::memcpy(&x, &input, 4);
    return _mm256_fmadd_ps(weights, _mm256_set1_ps(x), acc);
  }
  static void StoreHidden(Acc acc, uint32_t* out) {
    _mm256_storeu_ps(reinterpret_cast<float*>(out), _mm256_max_ps(acc, _mm256_setzero_ps()));
  }
  static void StoreFirst(Acc acc, float* out, int count) {
    const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    _mm256_maskstore_ps(out, _mm256_cmpgt_epi32(_mm256_set1_epi32(count), lanes), acc);
  }
};
#endif

constexpr int kLanes = Kernel::kLanes;
constexpr int kWordsPerBlock = kLanes / Kernel::kPerWord;  // words of a block of rows stored as inputs

// One layer's rows [kLanes first_block, kLanes (first_block + kRows)) for kSamples samples: in + c * stride holds
// sample c's input words. Hidden layers write ReLU of the result as the next layer's input words (stride words a
// sample), the last one floats (the first `count` samples, `rows` values each). Not inlined: inlined, GCC 12 kept
// the accumulators on the stack.
template <int kRows, int kSamples = Kernel::Samples(kRows)>
[[gnu::noinline]] void Tile(const uint32_t* weights, const float* bias, int groups, int row_stride, int first_block,
                            const uint32_t* in, int stride, bool last, uint32_t* hidden_out, float* out, int rows,
                            int count) {
  typename Kernel::Acc acc[kRows][kSamples];
  for (int r = 0; r < kRows; ++r) {
    const typename Kernel::Acc b = Kernel::Load(bias + (first_block + r) * kLanes);
    for (int c = 0; c < kSamples; ++c) acc[r][c] = b;
  }
  for (int g = 0; g < groups; ++g) {
    typename Kernel::Weights w[kRows];
    for (int r = 0; r < kRows; ++r) {
      w[r] = Kernel::LoadWeights(weights + size_t(g) * row_stride + (first_block + r) * kLanes);
    }
    for (int c = 0; c < kSamples; ++c) {
      const uint32_t x = in[c * stride + g];
      for (int r = 0; r < kRows; ++r) acc[r][c] = Kernel::MulAdd(acc[r][c], w[r], x);
    }
  }
  for (int c = 0; c < kSamples; ++c) {
    for (int r = 0; r < kRows; ++r) {
      const int row = (first_block + r) * kLanes;
      if (!last) {
        Kernel::StoreHidden(acc[r][c], hidden_out + c * stride + row / Kernel::kPerWord);
      } else if (c < count && row < rows) {
        Kernel::StoreFirst(acc[r][c], out + size_t(c) * rows + row, std::min(kLanes, rows - row));
      }
    }
  }
}

// Tile<kRows> over `padded` samples (a multiple of kPadSamples), for 1 to kMaxRows row blocks.
template <int kRows = Kernel::kMaxRows>
void Tiles(int row_blocks, int padded, const uint32_t* weights, const float* bias, int groups, int row_stride,
           int first_block, const uint32_t* in, int stride, bool last, uint32_t* hidden_out, float* out, int rows,
           int count) {
  if constexpr (kRows > 1) {
    if (row_blocks < kRows) {
      return Tiles<kRows - 1>(row_blocks, padded, weights, bias, groups, row_stride, first_block, in, stride, last,
                              hidden_out, out, rows, count);
    }
  }
  for (int c = 0; c < padded; c += Kernel::Samples(kRows)) {
    Tile<kRows>(weights, bias, groups, row_stride, first_block, in + c * stride, stride, last, hidden_out + c * stride,
                out + size_t(c) * rows, rows, count - c);
  }
}
#endif

}  // namespace

const char* RenderMlp::Instructions() {
#ifdef P2N_RENDER_MLP
  return Kernel::kName;
#else
  return nullptr;
#endif
}

bool RenderMlp::Rounds() {
#ifdef P2N_RENDER_MLP
  return Kernel::kRounds;
#else
  return false;
#endif
}

RenderMlp::RenderMlp(const Mlp<float>& mlp) : output_activation_(mlp.config().output_activation) {
#ifdef P2N_RENDER_MLP
  for (const Mlp<float>::Layer& source : mlp.layers()) {
    Layer layer;
    layer.inputs = source.inputs;
    layer.outputs = source.outputs;
    layer.groups = (source.inputs + Kernel::kPerWord - 1) / Kernel::kPerWord;
    layer.row_blocks = (source.outputs + kLanes - 1) / kLanes;
    const int row_stride = layer.row_blocks * kLanes;
    layer.words.assign(size_t(layer.groups) * row_stride, 0);
    layer.bias.assign(row_stride, 0.0f);
    const float* weight = mlp.params() + source.weight_offset;
    for (int g = 0; g < layer.groups; ++g) {
      for (int row = 0; row < source.outputs; ++row) {
        float values[Kernel::kPerWord] = {};
        for (int k = g * Kernel::kPerWord; k < std::min(source.inputs, (g + 1) * Kernel::kPerWord); ++k) {
          values[k % Kernel::kPerWord] = weight[row + size_t(k) * source.outputs];
        }
        layer.words[size_t(g) * row_stride + row] = Kernel::Word(values);
      }
    }
    std::copy_n(mlp.params() + source.bias_offset, source.outputs, layer.bias.begin());
    layers_.push_back(std::move(layer));
  }
#else
  throw std::logic_error("RenderMlp: this build has neither AVX-512 BF16 nor AVX2");
#endif
}

void RenderMlp::Forward(const float* input, Eigen::Index n, float* output) const {
#ifdef P2N_RENDER_MLP
  int stride = 0;  // words a sample in the activation buffers
  for (const Layer& layer : layers_) stride = std::max({stride, layer.groups, layer.row_blocks * kWordsPerBlock});
  std::vector<uint32_t> current(kBlockSamples * stride), next(kBlockSamples * stride);
  const int inputs = layers_.front().inputs, groups = layers_.front().groups, outputs = layers_.back().outputs;
  for (Eigen::Index first = 0; first < n; first += kBlockSamples) {
    const int count = static_cast<int>(std::min(kBlockSamples, n - first));
    const int padded = (count + Kernel::kPadSamples - 1) / Kernel::kPadSamples * Kernel::kPadSamples;
    std::fill(current.begin(), current.end(), 0);
    for (int c = 0; c < count; ++c) {
      const float* sample = input + (first + c) * inputs;
      for (int g = 0; g < groups; ++g) {
        float values[Kernel::kPerWord] = {};
        std::copy_n(sample + g * Kernel::kPerWord, std::min(Kernel::kPerWord, inputs - g * Kernel::kPerWord), values);
        current[c * stride + g] = Kernel::Word(values);
      }
    }
    for (size_t l = 0; l < layers_.size(); ++l) {
      const Layer& layer = layers_[l];
      const bool last = l + 1 == layers_.size();
      for (int block = 0; block < layer.row_blocks; block += Kernel::kMaxRows) {
        Tiles(std::min(Kernel::kMaxRows, layer.row_blocks - block), padded, layer.words.data(), layer.bias.data(),
              layer.groups, layer.row_blocks * kLanes, block, current.data(), stride, last, next.data(),
              output + first * outputs, outputs, count);
      }
      std::swap(current, next);
    }
  }
  Eigen::Map<Eigen::ArrayXf> values(output, n * outputs);
  if (output_activation_ == OutputActivation::kSigmoid) {
    values = (1.0f + (-values.max(-60.0f).min(60.0f)).exp()).inverse();  // as Mlp::Forward
  } else if (output_activation_ == OutputActivation::kRelu) {
    values = values.max(0.0f);
  }
#else
  (void)input;
  (void)n;
  (void)output;
  throw std::logic_error("RenderMlp: this build has neither AVX-512 BF16 nor AVX2");
#endif
}

}  // namespace p2n
