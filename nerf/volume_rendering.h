#pragma once
// Volume rendering of one ray from its samples (docs/design.md §6, numerics): alpha_i = 1 - exp(-sigma_i delta_i)
// computed as -expm1(-sigma_i delta_i), transmittance in log space (a running sum of sigma delta, never a long
// product of (1 - alpha)), the background as an explicit term weighted by the final transmittance, and early
// termination once the transmittance falls below a threshold. Compositing with exp(-sigma delta) is exact for
// density that is constant over each segment, at any step size; an explicit-Euler form (alpha = sigma delta)
// is not, and is not used.
//
// Gradients are analytic: with w_i = T_i - T_{i+1} and R_k the colour composited behind sample k (background
// included), dC/d(sigma_k delta_k) = T_{k+1} c_k - R_k; computed in one reverse pass.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace p2n {

// Optical depth sigma * delta of a segment: finite and non-negative whatever the inputs (NaN density counts as none).
template <typename T>
T OpticalDepth(T sigma, T delta) {
  const T s = std::max(sigma, T(0)) * std::max(delta, T(0));
  return std::isnan(s) ? T(0) : std::min(s, std::numeric_limits<T>::max());
}

template <typename T>
struct RaySegments {
  const T* sigma;  // density of each segment (>= 0; negative is treated as 0)
  const T* rgb;    // colour of each segment, 3 values each
  const T* t;      // distance of each sample along the ray (for depth)
  const T* delta;  // length of each segment (>= 0)
  size_t count;
};

template <typename T>
struct CompositeResult {
  T rgb[3] = {0, 0, 0};
  T opacity = 0;        // 1 - final transmittance
  T depth = 0;          // expected distance of the samples, sum w_i t_i (not normalised by opacity)
  T median_depth = -1;  // distance of the sample where the opacity first reaches one half; -1: it never does
  size_t used = 0;      // samples before early termination
  T transmittance = 1;  // after the used samples
};

// The running form of Composite(), for renderers that evaluate a ray's samples in rounds: Add() the segments
// in order while !Done(), then Finish() adds the background.
template <typename T>
class CompositeAccumulator {
 public:
  bool Done(T min_transmittance) const { return std::exp(log_transmittance_) < min_transmittance; }
  void Add(T sigma, const T* rgb, T t, T delta);
  CompositeResult<T> Finish(const T* background) const;

 private:
  CompositeResult<T> result_;
  T log_transmittance_ = 0;  // -sum sigma delta so far
};

// Composites the segments over `background` (3 values). Stops once the transmittance falls below
// `min_transmittance` (0: never).
template <typename T>
CompositeResult<T> Composite(const RaySegments<T>& ray, const T* background, T min_transmittance);

// Gradients of a loss L given dL/d(rgb) (3), dL/d(opacity) and dL/d(depth): writes dL/d(sigma_i) and
// dL/d(rgb_i) (3 each) for every segment (zero beyond `forward.used`).
template <typename T>
void CompositeBackward(const RaySegments<T>& ray, const T* background, const CompositeResult<T>& forward,
                       const T* d_rgb, T d_opacity, T d_depth, T* d_sigma, T* d_segment_rgb);

extern template class CompositeAccumulator<float>;
extern template class CompositeAccumulator<double>;
extern template CompositeResult<float> Composite(const RaySegments<float>&, const float*, float);
extern template CompositeResult<double> Composite(const RaySegments<double>&, const double*, double);
extern template void CompositeBackward(const RaySegments<float>&, const float*, const CompositeResult<float>&,
                                       const float*, float, float, float*, float*);
extern template void CompositeBackward(const RaySegments<double>&, const double*, const CompositeResult<double>&,
                                       const double*, double, double, double*, double*);

}  // namespace p2n
