#include "nerf/mlp.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "nerf/mlp_kernels.h"

namespace p2n {
namespace {

template <typename T>
using MatrixOf = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;
template <typename T>
using WeightMap = Eigen::Map<const MatrixOf<T>>;

// out = weight in + bias, then ReLU where `relu`: mlp_kernels' products for float in a build with them, Eigen's
// otherwise.
template <typename T>
void AffineLayer(const WeightMap<T>& weight, const T* bias, const MatrixOf<T>& in, bool relu, MatrixOf<T>* out) {
  if constexpr (std::is_same_v<T, float>) {
    if (mlp_kernels::Available()) {
      out->resize(weight.rows(), in.cols());
      mlp_kernels::LayerForward(weight.data(), bias, weight.rows(), weight.cols(), in.data(), in.cols(), relu,
                                out->data());
      return;
    }
  }
  out->noalias() = weight * in;
  out->colwise() += Eigen::Map<const Eigen::Matrix<T, Eigen::Dynamic, 1>>(bias, weight.rows());
  if (relu) *out = out->cwiseMax(T(0));
}

// Adds the layer's parameter gradients (d_weight += delta in^T, d_bias += delta's column sum) and, given d_in,
// writes the first `d_in_rows` rows of weight^T delta there, zero where the layer's input is not positive when
// `relu_input` (ReLU's gradient; fewer rows than inputs only without it: the kernel reads the mask with the rows'
// stride).
template <typename T>
void LayerBackward(const WeightMap<T>& weight, const MatrixOf<T>& in, const MatrixOf<T>& delta, bool relu_input,
                   T* d_weight, T* d_bias, MatrixOf<T>* d_in, int d_in_rows) {
  const int outputs = static_cast<int>(weight.rows()), inputs = static_cast<int>(weight.cols());
  if constexpr (std::is_same_v<T, float>) {
    if (mlp_kernels::Available()) {
      mlp_kernels::AddLayerGradient(delta.data(), outputs, in.data(), inputs, delta.cols(), d_weight, d_bias);
      if (d_in == nullptr) return;
      d_in->resize(d_in_rows, delta.cols());
      // The weight's first d_in_rows columns, as the whole weight but fewer rows of the result.
      mlp_kernels::LayerInputGradient(weight.data(), outputs, d_in_rows, delta.data(), delta.cols(),
                                      relu_input ? in.data() : nullptr, d_in->data());
      return;
    }
  }
  Eigen::Map<MatrixOf<T>>(d_weight, outputs, inputs).noalias() += delta * in.transpose();
  // Column by column: a fixed summation order (Eigen's vectorised reductions depend on memory alignment, which
  // would make training runs differ).
  Eigen::Map<Eigen::Matrix<T, Eigen::Dynamic, 1>> bias_gradient(d_bias, outputs);
  for (Eigen::Index j = 0; j < delta.cols(); ++j) bias_gradient += delta.col(j);
  if (d_in == nullptr) return;
  *d_in = weight.leftCols(d_in_rows).transpose() * delta;
  if (relu_input) *d_in = (in.topRows(d_in_rows).array() > T(0)).select(*d_in, T(0));
}

}  // namespace

nlohmann::json MlpConfig::ToJson() const {
  return {{"otype", "FullyConnected"},
          {"inputs", inputs},
          {"outputs", outputs},
          {"width", width},
          {"hidden_layers", hidden_layers},
          {"activation", "ReLU"},
          {"output_activation", output_activation == OutputActivation::kSigmoid ? "Sigmoid"
                                : output_activation == OutputActivation::kRelu  ? "ReLU"
                                                                                : "None"}};
}

template <typename T>
Mlp<T>::Mlp(const MlpConfig& config, uint64_t seed) : config_(config) {
  if (config.inputs <= 0 || config.outputs <= 0 || config.width <= 0 || config.hidden_layers < 0 ||
      config.inputs > 65536 || config.outputs > 65536 || config.width > 4096 || config.hidden_layers > 64) {
    throw std::invalid_argument(
        "MLP sizes must be positive and at most 65536 inputs and outputs, 4096 wide, 64 "
        "hidden layers: " +
        config.ToJson().dump());
  }
  size_t offset = 0;
  int inputs = config.inputs;
  for (int i = 0; i <= config.hidden_layers; ++i) {
    const int outputs = i == config.hidden_layers ? config.outputs : config.width;
    layers_.push_back({inputs, outputs, offset, offset + static_cast<size_t>(inputs) * outputs});
    offset += static_cast<size_t>(inputs) * outputs + outputs;
    inputs = outputs;
  }
  if (offset > (size_t{1} << 27))
    throw std::invalid_argument("MLP: more than 2^27 parameters " + config.ToJson().dump());
  params_.assign(offset, T(0));
  std::mt19937_64 random(seed);
  for (const Layer& layer : layers_) {
    const double bound = 1.0 / std::sqrt(layer.inputs);
    std::uniform_real_distribution<double> uniform(-bound, bound);
    for (size_t k = 0; k < static_cast<size_t>(layer.inputs) * layer.outputs + layer.outputs; ++k) {
      params_[layer.weight_offset + k] = static_cast<T>(uniform(random));
    }
  }
}

template <typename T>
void Mlp<T>::Forward(const Matrix& input, Matrix* output, Cache* cache) const {
  *output = Forward(Matrix(input), cache);
}

template <typename T>
const typename Mlp<T>::Matrix& Mlp<T>::Forward(Matrix input, Cache* cache) const {
  cache->activations.resize(layers_.size() + 1);
  cache->activations[0] = std::move(input);
  for (size_t i = 0; i < layers_.size(); ++i) {
    const Layer& layer = layers_[i];
    const Eigen::Map<const Matrix> weight(params_.data() + layer.weight_offset, layer.outputs, layer.inputs);
    Matrix& out = cache->activations[i + 1];
    const bool relu = i + 1 < layers_.size() || config_.output_activation == OutputActivation::kRelu;
    AffineLayer<T>(weight, params_.data() + layer.bias_offset, cache->activations[i], relu, &out);
    if (!relu && config_.output_activation == OutputActivation::kSigmoid) {
      // 1 / (1 + exp(-x)), with the exponent clamped so that no step overflows.
      out = (T(1) + (-out.array().max(T(-60)).min(T(60))).exp()).inverse().matrix();
    }
  }
  return cache->activations.back();
}

template <typename T>
void Mlp<T>::Backward(const Cache& cache, const Matrix& d_output, T* d_params, Matrix* d_input, int input_rows) const {
  Matrix delta = d_output;
  if (config_.output_activation == OutputActivation::kSigmoid) {
    const Matrix& s = cache.activations.back();
    delta = (delta.array() * s.array() * (T(1) - s.array())).matrix();
  } else if (config_.output_activation == OutputActivation::kRelu) {
    delta = (cache.activations.back().array() > T(0)).select(delta, T(0));
  }
  for (size_t i = layers_.size(); i-- > 0;) {
    const Layer& layer = layers_[i];
    const Eigen::Map<const Matrix> weight(params_.data() + layer.weight_offset, layer.outputs, layer.inputs);
    const bool input_wanted = i > 0 || d_input != nullptr;
    Matrix previous;
    // ReLU before every layer but the first.
    const int rows = i == 0 && input_rows >= 0 ? std::min(input_rows, layer.inputs) : layer.inputs;
    LayerBackward<T>(weight, cache.activations[i], delta, i > 0, d_params + layer.weight_offset,
                     d_params + layer.bias_offset, input_wanted ? &previous : nullptr, rows);
    if (!input_wanted) break;
    delta = std::move(previous);
  }
  if (d_input != nullptr) *d_input = std::move(delta);
}

template class Mlp<float>;
template class Mlp<double>;

}  // namespace p2n
