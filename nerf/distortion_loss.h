#pragma once
// The distortion loss of mip-NeRF 360 (Barron et al. 2022, eq. 15), in its linear-time form: for one ray whose
// samples have volume-rendering weights w_i over intervals of midpoint m_i (non-decreasing) and length l_i,
//   L = sum_{i,j} w_i w_j |m_i - m_j| + 1/3 sum_i w_i^2 l_i.
// It is small when a ray's weight sits in one short interval (a surface) and grows with weight spread along the
// ray (haze, floaters in front of the surface), which is what keeps rays from terminating early. The distances
// are in whatever metric the caller chooses; the trainer uses the sampler's (SamplingDistance), in which every
// sample costs the same.
//
// With the prefix sums W_<k = sum_{i<k} w_i and M_<k = sum_{i<k} w_i m_i (and the suffix sums likewise),
//   L = 2 sum_k w_k (m_k W_<k - M_<k) + 1/3 sum_k w_k^2 l_k,
//   dL/dw_k = 2 (m_k W_<k - M_<k) + 2 (M_>k - m_k W_>k) + 2/3 w_k l_k,
// and through w_k = T_k (1 - exp(-sigma_k delta_k)) the gradient reaches the densities as a colour does in
// CompositeBackward: dL/d(sigma_j delta_j) = T_{j+1} g_j - sum_{k>j} w_k g_k, with g = dL/dw.

#include <cstddef>

#include "nerf/volume_rendering.h"

namespace p2n {

// The loss of the first `count` segments of `ray` (those before early termination), with `midpoints` and
// `lengths` of each in the chosen metric. When `d_sigma` is not null, adds `scale` x dL/d(sigma_i) to it.
template <typename T>
T DistortionLoss(const RaySegments<T>& ray, size_t count, const T* midpoints, const T* lengths, T scale, T* d_sigma);

extern template float DistortionLoss(const RaySegments<float>&, size_t, const float*, const float*, float, float*);
extern template double DistortionLoss(const RaySegments<double>&, size_t, const double*, const double*, double,
                                      double*);

}  // namespace p2n
