#pragma once
// The rasterizer's lanes: a strip of a tile row's pixels as one value of GCC's vector extensions, one register of
// floats (16 with AVX-512, else 8: a row's blend state is seven such values, and 16 lanes on AVX2 would take two
// registers each, more than its 16 hold), so that blending a splat into a strip is a handful of vector
// instructions whether or not the auto-vectoriser sees it. Masks are the lane-wise comparisons' results (all bits
// set or none).

#include <immintrin.h>

#include <cmath>
#include <cstdint>
#include <type_traits>

namespace p2n::lanes {

#ifdef __AVX512F__
inline constexpr int kLanes = 16;
#else
inline constexpr int kLanes = 8;
#endif

template <typename T>
struct Types;
template <>
struct Types<float> {
  typedef float V __attribute__((vector_size(kLanes * sizeof(float))));
  typedef int32_t M __attribute__((vector_size(kLanes * sizeof(int32_t))));
};
template <>
struct Types<double> {
  typedef double V __attribute__((vector_size(kLanes * sizeof(double))));
  typedef int64_t M __attribute__((vector_size(kLanes * sizeof(int64_t))));
};

template <typename T>
using V = typename Types<T>::V;
template <typename T>
using M = typename Types<T>::M;

template <typename T>
inline V<T> Splat(T value) {
  return V<T>{} + value;
}

// 0, 1, ..., kLanes - 1.
template <typename T>
inline V<T> Iota() {
  V<T> v;
  for (int l = 0; l < kLanes; ++l) v[l] = T(l);
  return v;
}

template <typename T>
inline V<T> Select(M<T> mask, V<T> a, V<T> b) {
  return mask ? a : b;
}

template <typename T>
inline V<T> Min(V<T> a, V<T> b) {
  return a < b ? a : b;
}

template <typename T>
inline T Sum(V<T> v) {
  T sum = 0;
  for (int l = 0; l < kLanes; ++l) sum += v[l];
  return sum;
}

// One test instruction where the mask fills a register (GCC reduces a mask lane by lane otherwise).
template <typename T>
inline bool Any(M<T> mask) {
#if defined(__AVX512F__)
  if constexpr (sizeof(M<T>) == 64) return _mm512_test_epi32_mask((__m512i)mask, (__m512i)mask) != 0;
#elif defined(__AVX__)
  if constexpr (sizeof(M<T>) == 32) return !_mm256_testz_si256((__m256i)mask, (__m256i)mask);
#endif
  for (int l = 0; l < kLanes; ++l) {
    if (mask[l]) return true;
  }
  return false;
}

// e^x for x <= 0. Float: Cephes' expf polynomial (relative error about 2e-7) with a round-to-nearest by
// truncation (valid for x <= 0); below -87 it gives about 1.6e-38, far under any alpha that counts. Double (the
// tests' precision): std::exp lane by lane.
template <typename T>
inline V<T> ExpNonPositive(V<T> x) {
  if constexpr (std::is_same_v<T, double>) {
    for (int l = 0; l < kLanes; ++l) x[l] = std::exp(x[l]);
    return x;
  } else {
    x = x < -87.0f ? Splat(-87.0f) : x;
    const M<float> n = __builtin_convertvector(x * 1.44269504088896341f - 0.5f, M<float>);
    const V<float> fn = __builtin_convertvector(n, V<float>);
    const V<float> r = x - fn * 0.693359375f + fn * 2.12194440e-4f;
    V<float> p = Splat(1.9875691500e-4f);
    p = p * r + 1.3981999507e-3f;
    p = p * r + 8.3334519073e-3f;
    p = p * r + 4.1665795894e-2f;
    p = p * r + 1.6666665459e-1f;
    p = p * r + 5.0000001201e-1f;
    p = p * r * r + r + 1.0f;
    return p * reinterpret_cast<const V<float>&>(static_cast<const M<float>&>((n + 127) << 23));
  }
}

}  // namespace p2n::lanes
