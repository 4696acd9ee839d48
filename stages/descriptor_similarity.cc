#include "stages/descriptor_similarity.h"

#if defined(__AVX512VNNI__) && defined(__AVX512BW__)
#define P2N_DESCRIPTOR_VNNI 1
#include <immintrin.h>
#endif

#include <algorithm>

namespace p2n {
namespace {

#ifdef P2N_DESCRIPTOR_VNNI
constexpr int kDims = 128, kGroups = kDims / 4;  // a 32-bit lane sums the products of 4 dimensions
constexpr Eigen::Index kLanes = 16, kRowTile = 4 * kLanes;

// Accumulates the 64 rows from `packed` (4 blocks of 16) against kColumns columns of b (as signed bytes, b - 128)
// and writes their products, adding the rows' bias back. Four row registers and 4 x kColumns accumulators.
template <int kColumns>
void Tile(const uint8_t* packed, const int32_t* bias, const int8_t* const* columns, float* out, Eigen::Index stride) {
  __m512i acc[4][kColumns];
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < kColumns; ++c) acc[r][c] = _mm512_setzero_si512();
  }
  for (int g = 0; g < kGroups; ++g) {
    __m512i rows[4];
    for (int r = 0; r < 4; ++r) rows[r] = _mm512_loadu_si512(packed + (r * kGroups + g) * 64);
    for (int c = 0; c < kColumns; ++c) {
      int32_t four;
      std::copy_n(columns[c] + 4 * g, 4, reinterpret_cast<int8_t*>(&four));
      const __m512i column = _mm512_set1_epi32(four);
      for (int r = 0; r < 4; ++r) acc[r][c] = _mm512_dpbusd_epi32(acc[r][c], rows[r], column);
    }
  }
  for (int r = 0; r < 4; ++r) {
    const __m512i row_bias = _mm512_loadu_si512(bias + r * kLanes);
    for (int c = 0; c < kColumns; ++c) {
      _mm512_storeu_ps(out + c * stride + r * kLanes, _mm512_cvtepi32_ps(_mm512_add_epi32(acc[r][c], row_bias)));
    }
  }
}

template <int kColumns>
void Tiles(const uint8_t* packed, const int32_t* bias, Eigen::Index row_tiles, const int8_t* const* columns, float* out,
           Eigen::Index stride) {
  for (Eigen::Index t = 0; t < row_tiles; ++t) {
    Tile<kColumns>(packed + t * 4 * kGroups * 64, bias + t * kRowTile, columns, out + t * kRowTile, stride);
  }
}

// Tiles<count> for a count of columns from 1 to kColumns.
template <int kColumns>
void TilesUpTo(int count, const uint8_t* packed, const int32_t* bias, Eigen::Index row_tiles,
               const int8_t* const* columns, float* out, Eigen::Index stride) {
  if constexpr (kColumns > 1) {
    if (count < kColumns) return TilesUpTo<kColumns - 1>(count, packed, bias, row_tiles, columns, out, stride);
  }
  Tiles<kColumns>(packed, bias, row_tiles, columns, out, stride);
}
#endif

}  // namespace

bool DescriptorSimilarity::UsesVnni() {
#ifdef P2N_DESCRIPTOR_VNNI
  return true;
#else
  return false;
#endif
}

DescriptorSimilarity::DescriptorSimilarity(const SiftDescriptors& a) : rows_(a.cols()) {
#ifdef P2N_DESCRIPTOR_VNNI
  stride_ = (rows_ + kRowTile - 1) / kRowTile * kRowTile;
  packed_.assign(stride_ * kDims, 0);
  row_bias_.assign(stride_, 0);
  for (Eigen::Index i = 0; i < rows_; ++i) {
    const Eigen::Index block = i / kLanes, lane = i % kLanes;
    int32_t sum = 0;
    for (int d = 0; d < kDims; ++d) {
      packed_[(block * kGroups + d / 4) * 64 + lane * 4 + d % 4] = a(d, i);
      sum += a(d, i);
    }
    row_bias_[i] = 128 * sum;
  }
#else
  stride_ = rows_;
  a_float_ = a.cast<float>().transpose();
#endif
}

void DescriptorSimilarity::Block(const SiftDescriptors& b, Eigen::Index first, Eigen::Index width, float* out) const {
#ifdef P2N_DESCRIPTOR_VNNI
  // a . b = a . (b - 128) + 128 sum(a): the products take one side signed.
  constexpr int kColumnTile = 6;
  std::vector<int8_t> shifted(static_cast<size_t>(width) * kDims);
  for (Eigen::Index j = 0; j < width; ++j) {
    for (int d = 0; d < kDims; ++d) shifted[j * kDims + d] = static_cast<int8_t>(b(d, first + j) ^ 0x80);
  }
  const Eigen::Index row_tiles = stride_ / kRowTile;
  for (Eigen::Index j = 0; j < width; j += kColumnTile) {
    const int8_t* columns[kColumnTile];
    const int count = static_cast<int>(std::min<Eigen::Index>(kColumnTile, width - j));
    for (int c = 0; c < count; ++c) columns[c] = shifted.data() + (j + c) * kDims;
    float* block_out = out + j * stride_;
    TilesUpTo<kColumnTile>(count, packed_.data(), row_bias_.data(), row_tiles, columns, block_out, stride_);
  }
#else
  Eigen::Map<Eigen::MatrixXf> result(out, stride_, width);
  result.noalias() = a_float_ * b.middleCols(first, width).cast<float>();
#endif
}

}  // namespace p2n
