#include "splat/similarity.h"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

#include "nerf/spherical_harmonics.h"

namespace p2n {
namespace {

// The matrix M that turns spherical-harmonic coefficients (SphericalHarmonics()'s basis, coefficients 1 to 15)
// with a rotation: Σ (M c)_k Y_k(R d) = Σ c_k Y_k(d) for every direction d. Solved by least squares over directions
// spread over the sphere; degrees do not mix, so the fit is exact to rounding.
Eigen::Matrix<double, 15, 15> ShTurn(const Eigen::Matrix3d& rotation) {
  constexpr int kDirections = 64;
  Eigen::Matrix<double, kDirections, 15> before, after;
  for (int i = 0; i < kDirections; ++i) {  // a Fibonacci lattice
    const double z = 1 - (2 * i + 1.0) / kDirections, r = std::sqrt(1 - z * z), angle = i * 2.399963229728653;
    const Eigen::Vector3d d(r * std::cos(angle), r * std::sin(angle), z), turned = rotation * d;
    double y[kSphericalHarmonicsCount], y_turned[kSphericalHarmonicsCount];
    SphericalHarmonics(d.x(), d.y(), d.z(), y);
    SphericalHarmonics(turned.x(), turned.y(), turned.z(), y_turned);
    for (int k = 1; k < kSphericalHarmonicsCount; ++k) before(i, k - 1) = y[k], after(i, k - 1) = y_turned[k];
  }
  // after M = before, column by column.
  return after.colPivHouseholderQr().solve(before);
}

}  // namespace

void ApplySimilarity(const Eigen::Matrix3d& linear, const Eigen::Vector3d& translation, Gaussians<float>* g) {
  const double determinant = linear.determinant();
  const double scale = std::cbrt(determinant);
  const Eigen::Matrix3d rotation = linear / scale;
  if (!(determinant > 0) || !(rotation * rotation.transpose()).isIdentity(1e-6)) {
    throw std::invalid_argument("ApplySimilarity: not a rotation times a positive scale");
  }
  const Eigen::Quaterniond turn(rotation);
  const float log_scale = static_cast<float>(std::log(scale));
  const int rest = g->coefficients() - 1;
  const Eigen::MatrixXd sh_turn = ShTurn(rotation).topLeftCorner(rest, rest);
  for (size_t i = 0; i < g->size(); ++i) {
    float* p = &g->positions[3 * i];
    const Eigen::Vector3d moved = linear * Eigen::Vector3d(p[0], p[1], p[2]) + translation;
    for (int a = 0; a < 3; ++a) p[a] = static_cast<float>(moved[a]), g->log_scales[3 * i + a] += log_scale;
    float* q = &g->rotations[4 * i];
    const Eigen::Quaterniond turned = turn * Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    q[0] = static_cast<float>(turned.w()), q[1] = static_cast<float>(turned.x());
    q[2] = static_cast<float>(turned.y()), q[3] = static_cast<float>(turned.z());
    float* sh = &g->sh_rest[3 * rest * i];  // coefficient k's channel c at 3 k + c
    for (int c = 0; c < 3 && rest > 0; ++c) {
      Eigen::VectorXd coefficients(rest);
      for (int k = 0; k < rest; ++k) coefficients[k] = sh[3 * k + c];
      const Eigen::VectorXd turned_coefficients = sh_turn * coefficients;
      for (int k = 0; k < rest; ++k) sh[3 * k + c] = static_cast<float>(turned_coefficients[k]);
    }
  }
}

}  // namespace p2n
