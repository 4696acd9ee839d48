#include "splat/gaussians.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace p2n {

template <typename T>
void Gaussians<T>::Resize(size_t count) {
  ForEachArray([count](std::vector<T>& values, int per) { values.resize(count * per, T(0)); });
}

template <typename T>
void Gaussians<T>::SetZero() {
  ForEachArray([](std::vector<T>& values, int) { std::fill(values.begin(), values.end(), T(0)); });
}

template <typename T>
void Gaussians<T>::Append(const Gaussians& other, size_t index) {
  if (other.sh_degree != sh_degree) throw std::invalid_argument("Gaussians::Append: the SH degrees differ");
  std::vector<const std::vector<T>*> from;
  other.ForEachArray([&](const std::vector<T>& values, int) { from.push_back(&values); });
  size_t array = 0;
  ForEachArray([&](std::vector<T>& values, int per) {
    const auto* begin = from[array++]->data() + index * per;
    values.insert(values.end(), begin, begin + per);
  });
}

template <typename T>
void Gaussians<T>::Filter(const std::vector<bool>& keep) {
  if (keep.size() != size()) throw std::invalid_argument("Gaussians::Filter: one flag per Gaussian");
  ForEachArray([&](std::vector<T>& values, int per) {
    size_t out = 0;
    for (size_t i = 0; i < keep.size(); ++i) {
      if (!keep[i]) continue;
      if (out != i) std::copy_n(values.begin() + i * per, per, values.begin() + out * per);
      ++out;
    }
    values.resize(out * per);
  });
}

void ApplySimilarity(const Eigen::Matrix3d& linear, const Eigen::Vector3d& translation, Gaussians<float>* g) {
  const double determinant = linear.determinant();
  const double scale = std::cbrt(determinant);
  const Eigen::Matrix3d rotation = linear / scale;
  if (!(determinant > 0) || !(rotation * rotation.transpose()).isIdentity(1e-6)) {
    throw std::invalid_argument("ApplySimilarity: not a rotation times a positive scale");
  }
  if (std::any_of(g->sh_rest.begin(), g->sh_rest.end(), [](float v) { return v != 0; })) {
    throw std::invalid_argument("ApplySimilarity: the higher SH coefficients would need turning");
  }
  const Eigen::Quaterniond turn(rotation);
  const float log_scale = static_cast<float>(std::log(scale));
  for (size_t i = 0; i < g->size(); ++i) {
    float* p = &g->positions[3 * i];
    const Eigen::Vector3d moved = linear * Eigen::Vector3d(p[0], p[1], p[2]) + translation;
    for (int a = 0; a < 3; ++a) p[a] = static_cast<float>(moved[a]), g->log_scales[3 * i + a] += log_scale;
    float* q = &g->rotations[4 * i];
    const Eigen::Quaterniond turned = turn * Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    q[0] = static_cast<float>(turned.w()), q[1] = static_cast<float>(turned.x());
    q[2] = static_cast<float>(turned.y()), q[3] = static_cast<float>(turned.z());
  }
}

template <typename T>
T Sigmoid(T x) {
  return T(1) / (T(1) + std::exp(-x));
}

template <typename T>
T Logit(T p) {
  return std::log(p / (T(1) - p));
}

template struct Gaussians<float>;
template struct Gaussians<double>;
template float Sigmoid(float);
template double Sigmoid(double);
template float Logit(float);
template double Logit(double);

}  // namespace p2n
