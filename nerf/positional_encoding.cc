#include <cmath>
#include <stdexcept>

#include "nerf/encoding.h"

namespace p2n {

template <typename T>
PositionalEncoding<T>::PositionalEncoding(int dims, int levels) : dims_(dims), levels_(levels) {
  if (dims <= 0 || levels < 0 || levels > 30) {
    throw std::invalid_argument("positional encoding: dims must be positive and levels in 0..30");
  }
}

template <typename T>
nlohmann::json PositionalEncoding<T>::Config() const {
  return {{"otype", "Frequency"}, {"dims", dims_}, {"levels", levels_}, {"include_input", true}};
}

template <typename T>
void PositionalEncoding<T>::Forward(const Matrix& input, Matrix* output) const {
  const Eigen::Index n = input.cols();
  output->resize(output_dims(), n);
  const Matrix& x = input;
  output->topRows(dims_) = x;
  for (int k = 0; k < levels_; ++k) {
    const T frequency = static_cast<T>(std::ldexp(M_PI, k));  // 2^k pi
    const Matrix angle = frequency * x;
    output->middleRows(dims_ * (1 + 2 * k), dims_) = angle.array().sin().matrix();
    output->middleRows(dims_ * (2 + 2 * k), dims_) = angle.array().cos().matrix();
  }
}

template class PositionalEncoding<float>;
template class PositionalEncoding<double>;

}  // namespace p2n
