#include "splat/projection.h"

#include <algorithm>
#include <cmath>

#include "nerf/spherical_harmonics.h"

namespace p2n {
namespace {

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;
template <typename T>
using Mat2 = Eigen::Matrix<T, 2, 2>;
template <typename T>
using Mat23 = Eigen::Matrix<T, 2, 3>;

// The quantities of the forward projection that the backward pass needs too.
template <typename T>
struct Forward {
  Vec3<T> t;       // the mean in camera axes
  T u = 0, v = 0;  // x/z and y/z where the Jacobian is taken (clamped)
  bool u_clamped = false, v_clamped = false;
  Eigen::Matrix<T, 4, 1> q;  // the unit quaternion (w, x, y, z)
  T q_norm = 1;              // 0 when the stored quaternion is degenerate (drawn as the identity)
  Mat3<T> rotation;
  Vec3<T> scale;
  Mat3<T> m;          // rotation · diag(scale): Σ = m mᵀ
  Mat23<T> jw;        // J W
  Mat2<T> cov2d;      // with the dilation
  Vec3<T> direction;  // unit, from the camera's centre to the mean
  T distance = 0;
  T basis[kSphericalHarmonicsCount];
  T rgb[3];  // before clamping at 0
};

template <typename T>
Mat3<T> RotationOfUnitQuaternion(const Eigen::Matrix<T, 4, 1>& q) {
  const T w = q[0], x = q[1], y = q[2], z = q[3];
  Mat3<T> r;
  r << 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),  //
      2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),   //
      2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y);
  return r;
}

// The gradient of a unit quaternion from the gradient `g` of its rotation matrix.
template <typename T>
Eigen::Matrix<T, 4, 1> UnitQuaternionGradient(const Eigen::Matrix<T, 4, 1>& q, const Mat3<T>& g) {
  const T w = q[0], x = q[1], y = q[2], z = q[3];
  Eigen::Matrix<T, 4, 1> d;
  d[0] = 2 * (-z * g(0, 1) + y * g(0, 2) + z * g(1, 0) - x * g(1, 2) - y * g(2, 0) + x * g(2, 1));
  d[1] = 2 * (y * g(0, 1) + z * g(0, 2) + y * g(1, 0) - 2 * x * g(1, 1) - w * g(1, 2) + z * g(2, 0) + w * g(2, 1) -
              2 * x * g(2, 2));
  d[2] = 2 * (-2 * y * g(0, 0) + x * g(0, 1) + w * g(0, 2) + x * g(1, 0) + z * g(1, 2) - w * g(2, 0) + z * g(2, 1) -
              2 * y * g(2, 2));
  d[3] = 2 * (-2 * z * g(0, 0) - w * g(0, 1) + x * g(0, 2) + w * g(1, 0) - 2 * z * g(1, 1) + y * g(1, 2) + x * g(2, 0) +
              y * g(2, 1));
  return d;
}

// The gradient of SphericalHarmonics()'s 16 values' weighted sum Σ weight_k · basis_k with respect to the
// direction (x, y, z), from the basis's polynomial form (its radial part is removed by the caller).
template <typename T>
Vec3<T> ShDirectionGradient(const Vec3<T>& d, const T* weight, int count) {
  const T x = d[0], y = d[1], z = d[2];
  const T c1 = T(0.48860251190291987), c4 = T(1.0925484305920792), c6 = T(0.31539156525252005),
          c8 = T(0.54627421529603959), c9 = T(0.59004358992664352), c10 = T(2.8906114426405538),
          c11 = T(0.45704579946446572), c12 = T(0.3731763325901154), c14 = T(1.4453057213202769);
  // d basis_k / d(x, y, z), k = 1..15, as rows.
  const T rows[16][3] = {{0, 0, 0},
                         {0, -c1, 0},
                         {0, 0, c1},
                         {-c1, 0, 0},
                         {c4 * y, c4 * x, 0},
                         {0, -c4 * z, -c4 * y},
                         {0, 0, 6 * c6 * z},
                         {-c4 * z, 0, -c4 * x},
                         {2 * c8 * x, -2 * c8 * y, 0},
                         {-6 * c9 * x * y, -c9 * (3 * x * x - 3 * y * y), 0},
                         {c10 * y * z, c10 * x * z, c10 * x * y},
                         {0, -c11 * (5 * z * z - 1), -10 * c11 * y * z},
                         {0, 0, c12 * (15 * z * z - 3)},
                         {-c11 * (5 * z * z - 1), 0, -10 * c11 * x * z},
                         {2 * c14 * x * z, -2 * c14 * y * z, c14 * (x * x - y * y)},
                         {-c9 * (3 * x * x - 3 * y * y), 6 * c9 * x * y, 0}};
  Vec3<T> g = Vec3<T>::Zero();
  for (int k = 1; k < count; ++k) g += weight[k] * Vec3<T>(rows[k][0], rows[k][1], rows[k][2]);
  return g;
}

// The forward projection of Gaussian `i` up to its 2D covariance and colour; false when it is not drawn.
template <typename T>
bool ComputeForward(const Gaussians<T>& g, size_t i, const SplatCamera<T>& camera, const ProjectionOptions& options,
                    Forward<T>* f) {
  const Vec3<T> p(g.positions[3 * i], g.positions[3 * i + 1], g.positions[3 * i + 2]);
  f->t = camera.rotation * p + camera.translation;
  if (!(f->t.z() >= T(options.near)) || !f->t.allFinite()) return false;
  const T inv_z = 1 / f->t.z();
  const T u = f->t.x() * inv_z, v = f->t.y() * inv_z;
  f->u = std::clamp(u, camera.min_x, camera.max_x);
  f->v = std::clamp(v, camera.min_y, camera.max_y);
  f->u_clamped = f->u != u;
  f->v_clamped = f->v != v;
  Mat23<T> jacobian;
  jacobian << camera.fx * inv_z, 0, -camera.fx * f->u * inv_z, 0, camera.fy * inv_z, -camera.fy * f->v * inv_z;

  const Eigen::Matrix<T, 4, 1> q(g.rotations[4 * i], g.rotations[4 * i + 1], g.rotations[4 * i + 2],
                                 g.rotations[4 * i + 3]);
  f->q_norm = q.norm();
  const bool degenerate = !(f->q_norm > T(1e-12)) || !std::isfinite(f->q_norm);
  f->q = degenerate ? Eigen::Matrix<T, 4, 1>(1, 0, 0, 0) : Eigen::Matrix<T, 4, 1>(q / f->q_norm);
  if (degenerate) f->q_norm = 0;
  f->rotation = RotationOfUnitQuaternion(f->q);
  for (int a = 0; a < 3; ++a) f->scale[a] = std::exp(g.log_scales[3 * i + a]);
  f->m = f->rotation * f->scale.asDiagonal();
  f->jw = jacobian * camera.rotation;
  const Mat23<T> jwm = f->jw * f->m;
  f->cov2d = jwm * jwm.transpose() + T(options.dilation) * Mat2<T>::Identity();
  if (!f->cov2d.allFinite()) return false;

  f->direction = p - camera.centre;
  f->distance = f->direction.norm();
  if (f->distance > 0) f->direction /= f->distance;
  SphericalHarmonics(f->direction[0], f->direction[1], f->direction[2], f->basis);
  const int count = ShCoefficients(std::min(options.sh_degree, g.sh_degree));
  const T* rest = g.sh_rest.data() + i * 3 * (g.coefficients() - 1);  // none at degree 0
  for (int c = 0; c < 3; ++c) {
    T value = T(0.5) + f->basis[0] * g.sh_dc[3 * i + c];
    for (int k = 1; k < count; ++k) value += f->basis[k] * rest[3 * (k - 1) + c];
    f->rgb[c] = value;
  }
  return true;
}

}  // namespace

template <typename T>
SplatCamera<T> SplatCamera<T>::From(const PinholeCamera& camera) {
  const Eigen::Matrix3d world_from_cam = camera.world_from_cam.topLeftCorner<3, 3>();
  const Eigen::Vector3d centre = camera.world_from_cam.topRightCorner<3, 1>();
  const Eigen::Matrix3d cam_from_world = OpenCvFromOpenGlCamera() * world_from_cam.transpose();
  SplatCamera<T> out;
  out.rotation = cam_from_world.cast<T>();
  out.translation = (-cam_from_world * centre).cast<T>();
  out.centre = centre.cast<T>();
  out.fx = T(camera.fx);
  out.fy = T(camera.fy);
  out.cx = T(camera.cx);
  out.cy = T(camera.cy);
  out.width = camera.width;
  out.height = camera.height;
  const double margin_x = 0.3 * camera.width / camera.fx, margin_y = 0.3 * camera.height / camera.fy;
  out.min_x = T(-camera.cx / camera.fx - margin_x);
  out.max_x = T((camera.width - camera.cx) / camera.fx + margin_x);
  out.min_y = T(-camera.cy / camera.fy - margin_y);
  out.max_y = T((camera.height - camera.cy) / camera.fy + margin_y);
  return out;
}

template <typename T>
bool ProjectGaussian(const Gaussians<T>& gaussians, size_t i, const SplatCamera<T>& camera,
                     const ProjectionOptions& options, Splat2D<T>* splat, T* depth, T* radius) {
  Forward<T> f;
  if (!ComputeForward(gaussians, i, camera, options, &f)) return false;
  const T a = f.cov2d(0, 0), b = f.cov2d(0, 1), c = f.cov2d(1, 1);
  const T det = a * c - b * b;
  if (!(det > 0) || !std::isfinite(det)) return false;
  const T inv_z = 1 / f.t.z();
  splat->x = camera.fx * f.t.x() * inv_z + camera.cx;
  splat->y = camera.fy * f.t.y() * inv_z + camera.cy;
  splat->conic_a = c / det;
  splat->conic_b = -b / det;
  splat->conic_c = a / det;
  splat->opacity = Sigmoid(gaussians.opacity_logits[i]);
  for (int k = 0; k < 3; ++k) splat->rgb[k] = std::max(f.rgb[k], T(0));
  const T mid = T(0.5) * (a + c);
  const T largest_eigenvalue = mid + std::sqrt(std::max(T(0.1), mid * mid - det));
  *depth = splat->depth = f.t.z();
  *radius = std::ceil(3 * std::sqrt(largest_eigenvalue));
  return std::isfinite(splat->x) && std::isfinite(splat->y) && std::isfinite(*radius);
}

template <typename T>
void ProjectGaussianBackward(const Gaussians<T>& gaussians, size_t i, const SplatCamera<T>& camera,
                             const ProjectionOptions& options, const Splat2D<T>& grad, Gaussians<T>* grads) {
  Forward<T> f;
  if (!ComputeForward(gaussians, i, camera, options, &f)) return;
  Vec3<T> d_position = Vec3<T>::Zero();

  // Colour: coefficients and the viewing direction.
  const int count = ShCoefficients(std::min(options.sh_degree, gaussians.sh_degree));
  const size_t rest = i * 3 * (gaussians.coefficients() - 1);
  T d_basis[kSphericalHarmonicsCount] = {};
  for (int c = 0; c < 3; ++c) {
    if (f.rgb[c] < 0) continue;
    grads->sh_dc[3 * i + c] += f.basis[0] * grad.rgb[c];
    for (int k = 1; k < count; ++k) {
      grads->sh_rest[rest + 3 * (k - 1) + c] += f.basis[k] * grad.rgb[c];
      d_basis[k] += gaussians.sh_rest[rest + 3 * (k - 1) + c] * grad.rgb[c];
    }
  }
  if (f.distance > 0 && count > 1) {
    const Vec3<T> d_direction = ShDirectionGradient(f.direction, d_basis, count);
    d_position += (d_direction - f.direction * f.direction.dot(d_direction)) / f.distance;
  }

  const T opacity = Sigmoid(gaussians.opacity_logits[i]);
  grads->opacity_logits[i] += grad.opacity * opacity * (1 - opacity);

  // Conic -> 2D covariance: d(C⁻¹) = -C⁻¹ dC C⁻¹; conic_b stands for both off-diagonal entries.
  const Mat2<T> conic = f.cov2d.inverse();
  Mat2<T> d_conic;
  d_conic << grad.conic_a, grad.conic_b / 2, grad.conic_b / 2, grad.conic_c;
  const Mat2<T> d_cov2d = -conic * d_conic * conic;

  // 2D covariance = (J W) Σ (J W)ᵀ + dilation.
  const Mat3<T> sigma = f.m * f.m.transpose();
  const Mat3<T> d_sigma = f.jw.transpose() * d_cov2d * f.jw;
  const Mat23<T> d_jw = 2 * d_cov2d * f.jw * sigma;
  const Mat23<T> d_jacobian = d_jw * camera.rotation.transpose();

  // The Jacobian's and the 2D mean's dependence on the camera-space mean t.
  const T z = f.t.z(), inv_z = 1 / z, inv_z2 = inv_z * inv_z;
  Vec3<T> d_t;
  d_t.x() = camera.fx * inv_z * grad.x;
  d_t.y() = camera.fy * inv_z * grad.y;
  d_t.z() = -(camera.fx * f.t.x() * grad.x + camera.fy * f.t.y() * grad.y) * inv_z2;
  const T du_dz = f.u_clamped ? T(0) : -f.u * inv_z, dv_dz = f.v_clamped ? T(0) : -f.v * inv_z;
  if (!f.u_clamped) d_t.x() += d_jacobian(0, 2) * (-camera.fx * inv_z2);
  if (!f.v_clamped) d_t.y() += d_jacobian(1, 2) * (-camera.fy * inv_z2);
  d_t.z() += d_jacobian(0, 0) * (-camera.fx * inv_z2) + d_jacobian(1, 1) * (-camera.fy * inv_z2) +
             d_jacobian(0, 2) * (-camera.fx * (du_dz * z - f.u) * inv_z2) +
             d_jacobian(1, 2) * (-camera.fy * (dv_dz * z - f.v) * inv_z2);
  d_position += camera.rotation.transpose() * d_t;
  for (int a = 0; a < 3; ++a) grads->positions[3 * i + a] += d_position[a];

  // Σ = m mᵀ with m = R diag(s).
  const Mat3<T> d_m = 2 * d_sigma * f.m;
  for (int a = 0; a < 3; ++a) {
    grads->log_scales[3 * i + a] += f.rotation.col(a).dot(d_m.col(a)) * f.scale[a];
  }
  if (f.q_norm > 0) {
    const Mat3<T> d_rotation = d_m * f.scale.asDiagonal();
    const Eigen::Matrix<T, 4, 1> d_unit = UnitQuaternionGradient(f.q, d_rotation);
    const Eigen::Matrix<T, 4, 1> d_q = (d_unit - f.q * f.q.dot(d_unit)) / f.q_norm;
    for (int a = 0; a < 4; ++a) grads->rotations[4 * i + a] += d_q[a];
  }
}

#define P2N_INSTANTIATE(T)                                                                                            \
  template struct SplatCamera<T>;                                                                                     \
  template bool ProjectGaussian(const Gaussians<T>&, size_t, const SplatCamera<T>&, const ProjectionOptions&,         \
                                Splat2D<T>*, T*, T*);                                                                 \
  template void ProjectGaussianBackward(const Gaussians<T>&, size_t, const SplatCamera<T>&, const ProjectionOptions&, \
                                        const Splat2D<T>&, Gaussians<T>*);
P2N_INSTANTIATE(float)
P2N_INSTANTIATE(double)
#undef P2N_INSTANTIATE

}  // namespace p2n
