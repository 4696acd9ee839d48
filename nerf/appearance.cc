#include "nerf/appearance.h"

#include <Eigen/Dense>

namespace p2n {

std::vector<float> IdentityAppearance(size_t views) {
  std::vector<float> params(views * kAppearanceParams, 0.0f);
  for (size_t v = 0; v < views; ++v) {
    for (int c = 0; c < 3; ++c) params[v * kAppearanceParams + 4 * c] = 1.0f;
  }
  return params;
}

void CentreAppearance(std::vector<float>* params) {
  const size_t views = params->size() / kAppearanceParams;
  if (views == 0) return;
  const std::vector<float> identity = IdentityAppearance(1);
  for (int k = 0; k < kAppearanceParams; ++k) {
    double mean = 0;
    for (size_t v = 0; v < views; ++v) mean += (*params)[v * kAppearanceParams + k];
    const float shift = static_cast<float>(mean / static_cast<double>(views)) - identity[k];
    for (size_t v = 0; v < views; ++v) (*params)[v * kAppearanceParams + k] -= shift;
  }
}

void ApplyAppearance(const float* params, const float in[3], float out[3]) {
  for (int r = 0; r < 3; ++r) {
    out[r] = params[9 + r] + params[3 * r] * in[0] + params[3 * r + 1] * in[1] + params[3 * r + 2] * in[2];
  }
}

void AppearanceBackward(const float* params, const float in[3], const float d_out[3], float* grads, float d_in[3]) {
  for (int c = 0; c < 3; ++c) d_in[c] = 0;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      grads[3 * r + c] += d_out[r] * in[c];
      d_in[c] += params[3 * r + c] * d_out[r];
    }
    grads[9 + r] += d_out[r];
  }
}

std::vector<float> FitAppearance(const float* rendered, const float* target, size_t n) {
  // Normal equations of target_r = [rendered, 1] . theta_r for the three output channels at once, with a weak
  // pull towards the identity (ridge) so that a direction the pixels leave open (all of them grey, say) keeps it.
  const std::vector<float> identity = IdentityAppearance(1);
  Eigen::Matrix<double, 4, 3> prior = Eigen::Matrix<double, 4, 3>::Zero();
  prior.topRows<3>().setIdentity();
  const double ridge = 1e-6 * static_cast<double>(n) + 1e-9;
  Eigen::Matrix4d normal = ridge * Eigen::Matrix4d::Identity();
  Eigen::Matrix<double, 4, 3> right = ridge * prior;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector4d x(rendered[3 * i], rendered[3 * i + 1], rendered[3 * i + 2], 1.0);
    normal += x * x.transpose();
    right += x * Eigen::RowVector3d(target[3 * i], target[3 * i + 1], target[3 * i + 2]);
  }
  const Eigen::Matrix<double, 4, 3> theta = normal.llt().solve(right);
  if (!theta.allFinite()) return identity;
  std::vector<float> params(kAppearanceParams);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) params[3 * r + c] = static_cast<float>(theta(c, r));
    params[9 + r] = static_cast<float>(theta(3, r));
  }
  return params;
}

double AppearanceGain(const float* params) {
  const float white[3] = {1, 1, 1};
  float out[3];
  ApplyAppearance(params, white, out);
  return (out[0] + out[1] + out[2]) / 3.0;
}

}  // namespace p2n
