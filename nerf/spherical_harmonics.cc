#include "nerf/spherical_harmonics.h"

namespace p2n {

template <typename T>
void SphericalHarmonics(T x, T y, T z, T* out) {
  const T xx = x * x, yy = y * y, zz = z * z;
  out[0] = T(0.28209479177387814);       // 1 / (2 sqrt(pi))
  out[1] = T(-0.48860251190291987) * y;  // sqrt(3 / (4 pi))
  out[2] = T(0.48860251190291987) * z;
  out[3] = T(-0.48860251190291987) * x;
  out[4] = T(1.0925484305920792) * x * y;  // sqrt(15 / pi) / 2
  out[5] = T(-1.0925484305920792) * y * z;
  out[6] = T(0.31539156525252005) * (3 * zz - 1);  // sqrt(5 / pi) / 4
  out[7] = T(-1.0925484305920792) * x * z;
  out[8] = T(0.54627421529603959) * (xx - yy);           // sqrt(15 / pi) / 4
  out[9] = T(-0.59004358992664352) * y * (3 * xx - yy);  // sqrt(70 / pi) / 8
  out[10] = T(2.8906114426405538) * x * y * z;           // sqrt(105 / pi) / 2
  out[11] = T(-0.45704579946446572) * y * (5 * zz - 1);  // sqrt(42 / pi) / 8
  out[12] = T(0.3731763325901154) * z * (5 * zz - 3);    // sqrt(7 / pi) / 4
  out[13] = T(-0.45704579946446572) * x * (5 * zz - 1);
  out[14] = T(1.4453057213202769) * z * (xx - yy);  // sqrt(105 / pi) / 4
  out[15] = T(-0.59004358992664352) * x * (xx - 3 * yy);
}

template void SphericalHarmonics(float, float, float, float*);
template void SphericalHarmonics(double, double, double, double*);

}  // namespace p2n
