#pragma once
// Real spherical harmonics of a unit direction up to degree 3 (16 values): the direction encoding of the
// colour MLP (instant-ngp's "SphericalHarmonics" with degree 4). Fixed: no parameters.

#include <Eigen/Core>

namespace p2n {

inline constexpr int kSphericalHarmonicsCount = 16;

// Writes the 16 values for the unit direction (x, y, z) into `out`, in the usual order (l = 0..3, m = -l..l).
template <typename T>
void SphericalHarmonics(T x, T y, T z, T* out);

}  // namespace p2n
