#include "nerf/volume_rendering.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace p2n {

template <typename T>
void CompositeAccumulator<T>::Add(T sigma, const T* rgb, T t, T delta) {
  const T s = OpticalDepth(sigma, delta);
  const T weight = std::exp(log_transmittance_) * -std::expm1(-s);
  for (int c = 0; c < 3; ++c) result_.rgb[c] += weight * rgb[c];
  result_.depth += weight * t;
  if (result_.median_depth < 0 && log_transmittance_ - s <= -std::log(T(2))) result_.median_depth = t;
  log_transmittance_ -= s;
  ++result_.used;
}

template <typename T>
CompositeResult<T> CompositeAccumulator<T>::Finish(const T* background) const {
  CompositeResult<T> result = result_;
  result.transmittance = std::exp(log_transmittance_);
  result.opacity = -std::expm1(log_transmittance_);  // 1 - T, accurate when T is near 1
  for (int c = 0; c < 3; ++c) result.rgb[c] += result.transmittance * background[c];
  return result;
}

template <typename T>
CompositeResult<T> Composite(const RaySegments<T>& ray, const T* background, T min_transmittance) {
  CompositeAccumulator<T> accumulator;
  for (size_t i = 0; i < ray.count && !accumulator.Done(min_transmittance); ++i) {
    accumulator.Add(ray.sigma[i], ray.rgb + 3 * i, ray.t[i], ray.delta[i]);
  }
  return accumulator.Finish(background);
}

template <typename T>
void CompositeBackward(const RaySegments<T>& ray, const T* background, const CompositeResult<T>& forward,
                       const T* d_rgb, T d_opacity, T d_depth, T* d_sigma, T* d_segment_rgb) {
  std::fill(d_sigma, d_sigma + ray.count, T(0));
  std::fill(d_segment_rgb, d_segment_rgb + 3 * ray.count, T(0));
  // Behind sample k: R_k = sum_{i > k} w_i c_i + T_end * background, and the same for depth (no background).
  T behind_rgb[3];
  for (int c = 0; c < 3; ++c) behind_rgb[c] = forward.transmittance * background[c];
  T behind_depth = 0;
  // Transmittance before each used sample from the running sums (never by division, which fails once the
  // transmittance underflows).
  std::vector<T> log_before(forward.used + 1, T(0));
  for (size_t i = 0; i < forward.used; ++i)
    log_before[i + 1] = log_before[i] - OpticalDepth(ray.sigma[i], ray.delta[i]);
  for (size_t k = forward.used; k-- > 0;) {
    const T transmittance_before = std::exp(log_before[k]);
    const T transmittance_after = std::exp(log_before[k + 1]);
    const T s = OpticalDepth(ray.sigma[k], ray.delta[k]);
    const T weight = transmittance_before * -std::expm1(-s);
    T d_s = d_opacity * forward.transmittance;
    for (int c = 0; c < 3; ++c) {
      d_s += d_rgb[c] * (transmittance_after * ray.rgb[3 * k + c] - behind_rgb[c]);
      d_segment_rgb[3 * k + c] = d_rgb[c] * weight;
      behind_rgb[c] += weight * ray.rgb[3 * k + c];
    }
    d_s += d_depth * (transmittance_after * ray.t[k] - behind_depth);
    behind_depth += weight * ray.t[k];
    // s = sigma * delta; no gradient where the density was clamped at zero.
    d_sigma[k] = ray.sigma[k] > T(0) ? d_s * std::max(ray.delta[k], T(0)) : T(0);
  }
}

template class CompositeAccumulator<float>;
template class CompositeAccumulator<double>;
template CompositeResult<float> Composite(const RaySegments<float>&, const float*, float);
template CompositeResult<double> Composite(const RaySegments<double>&, const double*, double);
template void CompositeBackward(const RaySegments<float>&, const float*, const CompositeResult<float>&, const float*,
                                float, float, float*, float*);
template void CompositeBackward(const RaySegments<double>&, const double*, const CompositeResult<double>&,
                                const double*, double, double, double*, double*);

}  // namespace p2n
