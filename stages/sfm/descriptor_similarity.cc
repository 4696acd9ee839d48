#include "stages/sfm/descriptor_similarity.h"

#if (defined(__AVX512VNNI__) && defined(__AVX512BW__)) || defined(__AVX2__)
#define P2N_DESCRIPTOR_SIMD 1
#include <immintrin.h>
#endif

#include <algorithm>

namespace p2n {
namespace {

#ifdef P2N_DESCRIPTOR_SIMD
constexpr int kDims = 128;
// The integer kernels read both sides as 32-bit words, each holding kPerWord dimensions of one descriptor: a's
// packed per block of kLanes rows (the lanes of one register) and per group of kPerWord dimensions, b's one word a
// group, broadcast to every lane.
#if defined(__AVX512VNNI__) && defined(__AVX512BW__)
// AVX-512 VNNI: four byte products summed into each 32-bit lane (vpdpbusd), one side unsigned and one signed, so
// a . b = a . (b - 128) + 128 sum(a). 64 products an instruction.
struct Kernel {
  using Reg = __m512i;
  static constexpr int kLanes = 16, kPerWord = 4, kRowRegs = 4, kColumns = 6;
  static uint32_t RowWord(const uint8_t* d) { return Word(d[0], d[1], d[2], d[3]); }
  static uint32_t ColumnWord(const uint8_t* d) { return RowWord(d) ^ 0x80808080u; }
  static int32_t Bias(int32_t sum) { return 128 * sum; }
  static uint32_t Word(uint32_t a, uint32_t b, uint32_t c, uint32_t d) { return a | b << 8 | c << 16 | d << 24; }
  static Reg Zero() { return _mm512_setzero_si512(); }
  static Reg Load(const void* p) { return _mm512_loadu_si512(p); }
  static Reg Broadcast(uint32_t word) { return _mm512_set1_epi32(static_cast<int32_t>(word)); }
  static Reg MulAdd(Reg acc, Reg rows, Reg column) { return _mm512_dpbusd_epi32(acc, rows, column); }
  static void Store(float* out, Reg acc, Reg bias) {
    _mm512_storeu_ps(out, _mm512_cvtepi32_ps(_mm512_add_epi32(acc, bias)));
  }
};
#else
// AVX2: the bytes widened to 16 bits, two products summed into each 32-bit lane (vpmaddwd; 255 x 255 x 2 fits),
// then added: 16 products in two instructions, as many as a float multiply-add gives in one, with the port that
// float multiply-adds need left free on most x86 cores.
struct Kernel {
  using Reg = __m256i;
  static constexpr int kLanes = 8, kPerWord = 2, kRowRegs = 2, kColumns = 5;
  static uint32_t RowWord(const uint8_t* d) { return d[0] | uint32_t{d[1]} << 16; }
  static uint32_t ColumnWord(const uint8_t* d) { return RowWord(d); }
  static int32_t Bias(int32_t) { return 0; }
  static Reg Zero() { return _mm256_setzero_si256(); }
  static Reg Load(const void* p) { return _mm256_loadu_si256(static_cast<const __m256i*>(p)); }
  static Reg Broadcast(uint32_t word) { return _mm256_set1_epi32(static_cast<int32_t>(word)); }
  static Reg MulAdd(Reg acc, Reg rows, Reg column) { return _mm256_add_epi32(acc, _mm256_madd_epi16(rows, column)); }
  static void Store(float* out, Reg acc, Reg bias) {
    _mm256_storeu_ps(out, _mm256_cvtepi32_ps(_mm256_add_epi32(acc, bias)));
  }
};
#endif

constexpr int kGroups = kDims / Kernel::kPerWord;
constexpr Eigen::Index kRowTile = Kernel::kRowRegs * Kernel::kLanes;

// Accumulates one row tile (kRowRegs blocks of kLanes rows of `packed`) against kColumns columns of b (kGroups
// words each) and writes their products, adding the rows' bias. kRowRegs x kColumns accumulators in registers.
template <int kColumns>
void Tile(const uint32_t* packed, const int32_t* bias, const uint32_t* const* columns, float* out,
          Eigen::Index stride) {
  using Reg = Kernel::Reg;
  constexpr int kRows = Kernel::kRowRegs, kLanes = Kernel::kLanes;
  Reg acc[kRows][kColumns];
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kColumns; ++c) acc[r][c] = Kernel::Zero();
  }
  for (int g = 0; g < kGroups; ++g) {
    Reg rows[kRows];
    for (int r = 0; r < kRows; ++r) rows[r] = Kernel::Load(packed + (r * kGroups + g) * kLanes);
    for (int c = 0; c < kColumns; ++c) {
      const Reg column = Kernel::Broadcast(columns[c][g]);
      for (int r = 0; r < kRows; ++r) acc[r][c] = Kernel::MulAdd(acc[r][c], rows[r], column);
    }
  }
  for (int r = 0; r < kRows; ++r) {
    const Reg row_bias = Kernel::Load(bias + r * kLanes);
    for (int c = 0; c < kColumns; ++c) Kernel::Store(out + c * stride + r * kLanes, acc[r][c], row_bias);
  }
}

template <int kColumns>
void Tiles(const uint32_t* packed, const int32_t* bias, Eigen::Index row_tiles, const uint32_t* const* columns,
           float* out, Eigen::Index stride) {
  for (Eigen::Index t = 0; t < row_tiles; ++t) {
    Tile<kColumns>(packed + t * kRowTile * kGroups, bias + t * kRowTile, columns, out + t * kRowTile, stride);
  }
}

// Tiles<count> for a count of columns from 1 to kColumns.
template <int kColumns>
void TilesUpTo(int count, const uint32_t* packed, const int32_t* bias, Eigen::Index row_tiles,
               const uint32_t* const* columns, float* out, Eigen::Index stride) {
  if constexpr (kColumns > 1) {
    if (count < kColumns) return TilesUpTo<kColumns - 1>(count, packed, bias, row_tiles, columns, out, stride);
  }
  Tiles<kColumns>(packed, bias, row_tiles, columns, out, stride);
}
#endif

}  // namespace

const char* DescriptorSimilarity::Instructions() {
#if defined(__AVX512VNNI__) && defined(__AVX512BW__)
  return "AVX-512 VNNI";
#elif defined(__AVX2__)
  return "AVX2";
#else
  return "float";
#endif
}

DescriptorSimilarity::DescriptorSimilarity(const SiftDescriptors& a) : rows_(a.cols()) {
#ifdef P2N_DESCRIPTOR_SIMD
  stride_ = (rows_ + kRowTile - 1) / kRowTile * kRowTile;
  packed_.assign(stride_ * kGroups, 0);
  row_bias_.assign(stride_, 0);
  for (Eigen::Index i = 0; i < rows_; ++i) {
    const Eigen::Index block = i / Kernel::kLanes, lane = i % Kernel::kLanes;
    for (int g = 0; g < kGroups; ++g) {
      packed_[(block * kGroups + g) * Kernel::kLanes + lane] = Kernel::RowWord(&a(g * Kernel::kPerWord, i));
    }
    row_bias_[i] = Kernel::Bias(a.col(i).cast<int32_t>().sum());
  }
#else
  stride_ = rows_;
  a_float_ = a.cast<float>().transpose();
#endif
}

void DescriptorSimilarity::Block(const SiftDescriptors& b, Eigen::Index first, Eigen::Index width, float* out) const {
#ifdef P2N_DESCRIPTOR_SIMD
  std::vector<uint32_t> words(static_cast<size_t>(width) * kGroups);
  for (Eigen::Index j = 0; j < width; ++j) {
    for (int g = 0; g < kGroups; ++g) words[j * kGroups + g] = Kernel::ColumnWord(&b(g * Kernel::kPerWord, first + j));
  }
  const Eigen::Index row_tiles = stride_ / kRowTile;
  for (Eigen::Index j = 0; j < width; j += Kernel::kColumns) {
    const uint32_t* columns[Kernel::kColumns];
    const int count = static_cast<int>(std::min<Eigen::Index>(Kernel::kColumns, width - j));
    for (int c = 0; c < count; ++c) columns[c] = words.data() + (j + c) * kGroups;
    TilesUpTo<Kernel::kColumns>(count, packed_.data(), row_bias_.data(), row_tiles, columns, out + j * stride_,
                                stride_);
  }
#else
  Eigen::Map<Eigen::MatrixXf> result(out, stride_, width);
  result.noalias() = a_float_ * b.middleCols(first, width).cast<float>();
#endif
}

}  // namespace p2n
