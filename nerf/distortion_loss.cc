#include "nerf/distortion_loss.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace p2n {

template <typename T>
T DistortionLoss(const RaySegments<T>& ray, size_t count, const T* midpoints, const T* lengths, T scale, T* d_sigma) {
  count = std::min(count, ray.count);
  if (count == 0) return T(0);
  // Transmittance before each segment, from the running optical depth (never a product of 1 - alpha).
  std::vector<T> before(count + 1), weight(count);
  T log_transmittance = 0;
  for (size_t i = 0; i < count; ++i) {
    before[i] = std::exp(log_transmittance);
    const T s = OpticalDepth(ray.sigma[i], ray.delta[i]);
    weight[i] = before[i] * -std::expm1(-s);
    log_transmittance -= s;
  }
  before[count] = std::exp(log_transmittance);
  // Forward, keeping dL/dw_k's part from the samples in front (prefix sums).
  std::vector<T> d_weight(count);
  T loss = 0, w_front = 0, wm_front = 0;
  for (size_t k = 0; k < count; ++k) {
    const T front = midpoints[k] * w_front - wm_front;  // sum_{i<k} w_i (m_k - m_i) >= 0
    loss += 2 * weight[k] * front + weight[k] * weight[k] * lengths[k] / 3;
    d_weight[k] = 2 * front + T(2) / 3 * weight[k] * lengths[k];
    w_front += weight[k];
    wm_front += weight[k] * midpoints[k];
  }
  if (d_sigma == nullptr) return loss;
  // Backward: the part from the samples behind (suffix sums), then through the weights to the densities.
  T w_behind = 0, wm_behind = 0, weighted_g_behind = 0;
  for (size_t k = count; k-- > 0;) {
    d_weight[k] += 2 * (wm_behind - midpoints[k] * w_behind);
    w_behind += weight[k];
    wm_behind += weight[k] * midpoints[k];
    const T d_s = before[k + 1] * d_weight[k] - weighted_g_behind;
    weighted_g_behind += weight[k] * d_weight[k];
    if (ray.sigma[k] > T(0)) d_sigma[k] += scale * d_s * std::max(ray.delta[k], T(0));
  }
  return loss;
}

template float DistortionLoss(const RaySegments<float>&, size_t, const float*, const float*, float, float*);
template double DistortionLoss(const RaySegments<double>&, size_t, const double*, const double*, double, double*);

}  // namespace p2n
