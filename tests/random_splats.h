#pragma once
// Splats for the tests of the splat files: every parameter random, and how far apart two rotations are.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "splat/gaussians.h"

namespace p2n::testing {

// SH degree 3, positions, rotations, opacity logits and base colours in [-2, 2], log-scales in [-6, -2], higher
// SH coefficients in [-0.5, 0.5].
inline Gaussians<float> RandomSplats(int count, uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<float> uniform(-1, 1);
  Gaussians<float> g;
  g.Resize(count);
  for (std::vector<float>* values : {&g.positions, &g.rotations, &g.opacity_logits, &g.sh_dc}) {
    for (float& v : *values) v = 2 * uniform(random);
  }
  for (float& v : g.log_scales) v = -4 + 2 * uniform(random);
  for (float& v : g.sh_rest) v = 0.5f * uniform(random);
  return g;
}

// The largest difference between the quaternions a and b (w, x, y, z) once normalised, either sign.
inline float QuaternionError(const float* a, const float* b) {
  const float na = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + a[3] * a[3]);
  const float nb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2] + b[3] * b[3]);
  float same = 0, opposite = 0;
  for (int k = 0; k < 4; ++k) {
    same = std::max(same, std::abs(a[k] / na - b[k] / nb));
    opposite = std::max(opposite, std::abs(a[k] / na + b[k] / nb));
  }
  return std::min(same, opposite);
}

}  // namespace p2n::testing
