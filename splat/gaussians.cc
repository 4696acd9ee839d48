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
void Gaussians<T>::Append(const Gaussians& other) {
  if (other.sh_degree != sh_degree) throw std::invalid_argument("Gaussians::Append: the SH degrees differ");
  std::vector<const std::vector<T>*> from;
  other.ForEachArray([&](const std::vector<T>& values, int) { from.push_back(&values); });
  size_t array = 0;
  ForEachArray([&](std::vector<T>& values, int) {
    const std::vector<T>& source = *from[array++];
    values.insert(values.end(), source.begin(), source.end());
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
