#include "nerf/mlp_kernels.h"

#if defined(__AVX2__) && defined(__FMA__)
#define P2N_MLP_KERNELS 1
#include <immintrin.h>
#endif

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace p2n::mlp_kernels {
namespace {

#ifdef P2N_MLP_KERNELS
constexpr int kLanes = 8;                     // floats in a register
constexpr int kMaxRowBlocks = 2;              // a tile's rows: 16
constexpr int kMaxColumns = 6;                // and columns: 12 accumulators of AVX2's 16 registers
constexpr Eigen::Index kGradientBlock = 256;  // samples of dy packed at a time by AddLayerGradient (in L2)

enum class Epilogue { kNone, kRelu, kMask };

// One product C = init + sum over t of A_t B_t^T, tile by tile. A_t's rows are at a + t lda (packed: whole 8-row
// blocks readable); B's value for column c at t is b[c bc + t bt]; init (null: zero) for row r of column c is
// init[c init_c + r] (init_c 0: one bias for every column); C's column c goes to out + c out_c after the epilogue
// (ReLU, or zero where mask[c mask_c + r] is not positive); only its first `rows` rows are read or written.
struct Product {
  const float* a;
  size_t lda;
  int rows, depth;
  const float* b;
  size_t bc, bt;
  const float* init;
  size_t init_c;
  Epilogue epilogue;
  const float* mask;
  size_t mask_c;
  float* out;
  size_t out_c;
};

__m256i FirstLanes(int count) {
  return _mm256_cmpgt_epi32(_mm256_set1_epi32(count), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}

__m256 LoadRows(const float* p, int rows) {
  return rows >= kLanes ? _mm256_loadu_ps(p) : _mm256_maskload_ps(p, FirstLanes(rows));
}

void StoreRows(float* p, __m256 value, int rows) {
  if (rows >= kLanes) {
    _mm256_storeu_ps(p, value);
  } else {
    _mm256_maskstore_ps(p, FirstLanes(rows), value);
  }
}

// Rows [first_row, first_row + 8 kRowBlocks) of columns [column, column + kColumns). Not inlined, its loops over
// the tile unrolled and the product's fields read once, so that GCC keeps the accumulators in registers (without
// the pragmas it kept them on the stack, at half the speed).
template <int kRowBlocks, int kColumns>
[[gnu::noinline]] void Tile(const Product& p, int first_row, size_t column) {
  const size_t lda = p.lda, bc = p.bc, bt = p.bt;
  const int depth = p.depth;
  __m256 acc[kRowBlocks][kColumns];
#pragma GCC unroll 8
  for (int r = 0; r < kRowBlocks; ++r) {
    const int row = first_row + r * kLanes;
#pragma GCC unroll 8
    for (int c = 0; c < kColumns; ++c) {
      acc[r][c] =
          p.init != nullptr ? LoadRows(p.init + (column + c) * p.init_c + row, p.rows - row) : _mm256_setzero_ps();
    }
  }
  const float* a = p.a + first_row;
  const float* b = p.b + column * bc;
  for (int t = 0; t < depth; ++t, a += lda, b += bt) {
    __m256 w[kRowBlocks];
#pragma GCC unroll 8
    for (int r = 0; r < kRowBlocks; ++r) w[r] = _mm256_loadu_ps(a + r * kLanes);
#pragma GCC unroll 8
    for (int c = 0; c < kColumns; ++c) {
      const __m256 x = _mm256_broadcast_ss(b + c * bc);
#pragma GCC unroll 8
      for (int r = 0; r < kRowBlocks; ++r) acc[r][c] = _mm256_fmadd_ps(w[r], x, acc[r][c]);
    }
  }
#pragma GCC unroll 8
  for (int c = 0; c < kColumns; ++c) {
#pragma GCC unroll 8
    for (int r = 0; r < kRowBlocks; ++r) {
      const int row = first_row + r * kLanes;
      __m256 value = acc[r][c];
      if (p.epilogue == Epilogue::kRelu) {
        value = _mm256_max_ps(value, _mm256_setzero_ps());
      } else if (p.epilogue == Epilogue::kMask) {
        const __m256 mask = LoadRows(p.mask + (column + c) * p.mask_c + row, p.rows - row);
        value = _mm256_and_ps(value, _mm256_cmp_ps(mask, _mm256_setzero_ps(), _CMP_GT_OQ));
      }
      StoreRows(p.out + (column + c) * p.out_c + row, value, p.rows - row);
    }
  }
}

template <int kColumns>
void TileColumn(const Product& p, size_t column) {
  for (int row = 0; row < p.rows; row += kMaxRowBlocks * kLanes) {
    if (p.rows - row > kLanes) {
      Tile<2, kColumns>(p, row, column);
    } else {
      Tile<1, kColumns>(p, row, column);
    }
  }
}

void Run(const Product& p, size_t columns) {
  static_assert(kMaxRowBlocks == 2 && kMaxColumns == 6, "TileColumn and Run are written for 2 x 6 tiles");
  size_t column = 0;
  for (; column + kMaxColumns <= columns; column += kMaxColumns) TileColumn<kMaxColumns>(p, column);
  switch (columns - column) {
    case 5:
      return TileColumn<5>(p, column);
    case 4:
      return TileColumn<4>(p, column);
    case 3:
      return TileColumn<3>(p, column);
    case 2:
      return TileColumn<2>(p, column);
    case 1:
      return TileColumn<1>(p, column);
    default:
      return;
  }
}

int Padded(int rows) { return (rows + kLanes - 1) / kLanes * kLanes; }

// `columns` panels of Padded(rows) values into `panels`, zero-filled past `rows`: panel c holds source[r row_stride +
// c column_stride] for r < rows.
void Panels(const float* source, int rows, int columns, size_t row_stride, size_t column_stride,
            std::vector<float>* panels) {
  const int padded = Padded(rows);
  panels->assign(size_t(padded) * columns, 0.0f);
  for (int c = 0; c < columns; ++c) {
    for (int r = 0; r < rows; ++r) (*panels)[size_t(c) * padded + r] = source[r * row_stride + c * column_stride];
  }
}
#else
[[noreturn]] void Unavailable() { throw std::logic_error("mlp_kernels: this build has no AVX2 and FMA"); }
#endif

}  // namespace

bool Available() {
#ifdef P2N_MLP_KERNELS
  return true;
#else
  return false;
#endif
}

void LayerForward(const float* weight, const float* bias, int m, int k, const float* x, Eigen::Index n, bool relu,
                  float* y) {
#ifdef P2N_MLP_KERNELS
  std::vector<float> w;
  Panels(weight, m, k, 1, m, &w);  // panel t: W's column t
  Run({w.data(), size_t(Padded(m)), m, k, x, size_t(k), 1, bias, 0, relu ? Epilogue::kRelu : Epilogue::kNone, nullptr,
       0, y, size_t(m)},
      n);
#else
  (void)weight, (void)bias, (void)m, (void)k, (void)x, (void)n, (void)relu, (void)y;
  Unavailable();
#endif
}

void LayerInputGradient(const float* weight, int m, int k, const float* dy, Eigen::Index n, const float* mask,
                        float* dx) {
#ifdef P2N_MLP_KERNELS
  std::vector<float> w;
  Panels(weight, k, m, m, 1, &w);  // panel t: W's row t
  Run({w.data(), size_t(Padded(k)), k, m, dy, size_t(m), 1, nullptr, 0,
       mask != nullptr ? Epilogue::kMask : Epilogue::kNone, mask, size_t(k), dx, size_t(k)},
      n);
#else
  (void)weight, (void)m, (void)k, (void)dy, (void)n, (void)mask, (void)dx;
  Unavailable();
#endif
}

void AddLayerGradient(const float* dy, int m, const float* x, int k, Eigen::Index n, float* d_weight, float* d_bias) {
#ifdef P2N_MLP_KERNELS
  // Over blocks of samples: C = d_weight, depth the block's samples, A_t = dy's column t (packed), B(c, t) = x(c, t).
  std::vector<float> a;  // one allocation for every block
  for (Eigen::Index first = 0; first < n; first += kGradientBlock) {
    const int count = static_cast<int>(std::min(kGradientBlock, n - first));
    Panels(dy + first * m, m, count, 1, m, &a);
    Run({a.data(), size_t(Padded(m)), m, count, x + first * k, 1, size_t(k), d_weight, size_t(m), Epilogue::kNone,
         nullptr, 0, d_weight, size_t(m)},
        k);
  }
  for (Eigen::Index j = 0; j < n; ++j) {
    for (int r = 0; r < m; ++r) d_bias[r] += dy[j * m + r];
  }
#else
  (void)dy, (void)m, (void)x, (void)k, (void)n, (void)d_weight, (void)d_bias;
  Unavailable();
#endif
}

}  // namespace p2n::mlp_kernels
