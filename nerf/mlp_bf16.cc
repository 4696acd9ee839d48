#include "nerf/mlp_bf16.h"

#if defined(__AVX512BF16__) && defined(__AVX512BW__) && defined(__AVX512VL__)
#define P2N_MLP_BF16 1
#include <immintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace p2n {
namespace {

constexpr int kLanes = 16;         // floats in a vector register: a block of output rows
constexpr int kTileRowBlocks = 4;  // row blocks of a tile at most
// Samples of a tile of kRows row blocks: up to 24 accumulators in registers, and at least 12 (independent sums
// to keep the multiply-add units busy through their latency).
template <int kRows>
constexpr int kTileSamples = kRows <= 2 ? 12 : 24 / kRows;
constexpr int kPadSamples = 24;              // a multiple of every tile's samples
constexpr Eigen::Index kBlockSamples = 192;  // samples taken through every layer at a time (in the cache)

// bfloat16 of x, rounded to nearest even (as the instructions round).
uint16_t ToBf16(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, 4);
  return static_cast<uint16_t>((bits + 0x7fff + ((bits >> 16) & 1)) >> 16);
}

#ifdef P2N_MLP_BF16
// One layer's rows [16 first_block, 16 (first_block + kRows)) for kTileSamples samples: in + c * in_stride holds
// sample c's inputs (bfloat16, in pairs). Hidden layers write ReLU of the result as bfloat16 (out_stride values a
// sample), the last one floats (the first `count` samples, `rows` values each). Not inlined: inlined, GCC 12 kept
// the accumulators on the stack.
template <int kRows, int kSamples = kTileSamples<kRows>>
[[gnu::noinline]] void Tile(const uint16_t* weights, const float* bias, int pairs, int row_stride, int first_block,
                            const uint16_t* in, int in_stride, bool last, uint16_t* hidden_out, int out_stride,
                            float* out, int rows, int count) {
  __m512 acc[kRows][kSamples];
  for (int r = 0; r < kRows; ++r) {
    const __m512 b = _mm512_loadu_ps(bias + (first_block + r) * kLanes);
    for (int c = 0; c < kSamples; ++c) acc[r][c] = b;
  }
  for (int p = 0; p < pairs; ++p) {
    __m512bh w[kRows];
    for (int r = 0; r < kRows; ++r) {
      w[r] = (__m512bh)_mm512_loadu_si512(weights + (size_t(p) * row_stride + (first_block + r) * kLanes) * 2);
    }
    for (int c = 0; c < kSamples; ++c) {
      int32_t two;
      std::memcpy(&two, in + c * in_stride + 2 * p, 4);
      const __m512bh x = (__m512bh)_mm512_set1_epi32(two);
      for (int r = 0; r < kRows; ++r) acc[r][c] = _mm512_dpbf16_ps(acc[r][c], w[r], x);
    }
  }
  for (int c = 0; c < kSamples; ++c) {
    for (int r = 0; r < kRows; ++r) {
      const int row = (first_block + r) * kLanes;
      if (last) {
        if (c < count && row < rows) {
          const __mmask16 mask = static_cast<__mmask16>((1u << std::min(kLanes, rows - row)) - 1);
          _mm512_mask_storeu_ps(out + size_t(c) * rows + row, mask, acc[r][c]);
        }
      } else {
        const __m256bh packed = _mm512_cvtneps_pbh(_mm512_max_ps(acc[r][c], _mm512_setzero_ps()));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(hidden_out + c * out_stride + row), (__m256i)packed);
      }
    }
  }
}

// Tile<kRows> over `padded` samples (a multiple of kPadSamples), for 1 to kTileRowBlocks row blocks.
template <int kRows = kTileRowBlocks>
void Tiles(int row_blocks, int padded, const uint16_t* weights, const float* bias, int pairs, int row_stride,
           int first_block, const uint16_t* in, int stride, bool last, uint16_t* hidden_out, float* out, int rows,
           int count) {
  if constexpr (kRows > 1) {
    if (row_blocks < kRows) {
      return Tiles<kRows - 1>(row_blocks, padded, weights, bias, pairs, row_stride, first_block, in, stride, last,
                              hidden_out, out, rows, count);
    }
  }
  for (int c = 0; c < padded; c += kTileSamples<kRows>) {
    Tile<kRows>(weights, bias, pairs, row_stride, first_block, in + c * stride, stride, last, hidden_out + c * stride,
                stride, out + size_t(c) * rows, rows, count - c);
  }
}
#endif

}  // namespace

bool Bf16Mlp::Available() {
#ifdef P2N_MLP_BF16
  return true;
#else
  return false;
#endif
}

Bf16Mlp::Bf16Mlp(const Mlp<float>& mlp) : output_activation_(mlp.config().output_activation) {
  if (!Available()) throw std::logic_error("Bf16Mlp: this build has no AVX-512 BF16");
  for (const Mlp<float>::Layer& source : mlp.layers()) {
    Layer layer;
    layer.inputs = source.inputs;
    layer.outputs = source.outputs;
    layer.pairs = (source.inputs + 1) / 2;
    layer.row_blocks = (source.outputs + kLanes - 1) / kLanes;
    const int row_stride = layer.row_blocks * kLanes;
    layer.weights.assign(size_t(layer.pairs) * row_stride * 2, 0);
    layer.bias.assign(row_stride, 0.0f);
    const float* weight = mlp.params() + source.weight_offset;
    for (int k = 0; k < source.inputs; ++k) {
      for (int row = 0; row < source.outputs; ++row) {
        layer.weights[(size_t(k / 2) * row_stride + row) * 2 + k % 2] =
            ToBf16(weight[row + size_t(k) * source.outputs]);
      }
    }
    std::copy_n(mlp.params() + source.bias_offset, source.outputs, layer.bias.begin());
    layers_.push_back(std::move(layer));
  }
}

void Bf16Mlp::Forward(const float* input, Eigen::Index n, float* output) const {
#ifdef P2N_MLP_BF16
  int stride = 0;  // bfloat16 values a sample in the activation buffers
  for (const Layer& layer : layers_) stride = std::max({stride, 2 * layer.pairs, layer.row_blocks * kLanes});
  std::vector<uint16_t> current(kBlockSamples * stride), next(kBlockSamples * stride);
  const int inputs = layers_.front().inputs, outputs = layers_.back().outputs;
  for (Eigen::Index first = 0; first < n; first += kBlockSamples) {
    const int count = static_cast<int>(std::min(kBlockSamples, n - first));
    const int padded = (count + kPadSamples - 1) / kPadSamples * kPadSamples;
    std::fill(current.begin(), current.end(), 0);
    for (int c = 0; c < count; ++c) {
      for (int k = 0; k < inputs; k += kLanes) {
        const __mmask16 mask = static_cast<__mmask16>((1u << std::min(kLanes, inputs - k)) - 1);
        const __m256bh packed = _mm512_cvtneps_pbh(_mm512_maskz_loadu_ps(mask, input + (first + c) * inputs + k));
        _mm256_mask_storeu_epi16(current.data() + c * stride + k, mask, (__m256i)packed);
      }
    }
    for (size_t l = 0; l < layers_.size(); ++l) {
      const Layer& layer = layers_[l];
      const bool last = l + 1 == layers_.size();
      for (int block = 0; block < layer.row_blocks; block += kTileRowBlocks) {
        Tiles(std::min(kTileRowBlocks, layer.row_blocks - block), padded, layer.weights.data(), layer.bias.data(),
              layer.pairs, layer.row_blocks * kLanes, block, current.data(), stride, last, next.data(),
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
  throw std::logic_error("Bf16Mlp: this build has no AVX-512 BF16");
#endif
}

}  // namespace p2n
