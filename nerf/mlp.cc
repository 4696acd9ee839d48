#include "nerf/mlp.h"

#include <cmath>
#include <random>
#include <stdexcept>

namespace p2n {

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
  cache->activations.resize(layers_.size() + 1);
  cache->activations[0] = input;
  for (size_t i = 0; i < layers_.size(); ++i) {
    const Layer& layer = layers_[i];
    const Eigen::Map<const Matrix> weight(params_.data() + layer.weight_offset, layer.outputs, layer.inputs);
    const Eigen::Map<const Eigen::Matrix<T, Eigen::Dynamic, 1>> bias(params_.data() + layer.bias_offset, layer.outputs);
    Matrix& out = cache->activations[i + 1];
    out.noalias() = weight * cache->activations[i];
    out.colwise() += bias;
    if (i + 1 < layers_.size() || config_.output_activation == OutputActivation::kRelu) {
      out = out.cwiseMax(T(0));
    } else if (config_.output_activation == OutputActivation::kSigmoid) {
      // 1 / (1 + exp(-x)), with the exponent clamped so that no step overflows.
      out = (T(1) + (-out.array().max(T(-60)).min(T(60))).exp()).inverse().matrix();
    }
  }
  *output = cache->activations.back();
}

template <typename T>
void Mlp<T>::Backward(const Cache& cache, const Matrix& d_output, T* d_params, Matrix* d_input) const {
  Matrix delta = d_output;
  if (config_.output_activation == OutputActivation::kSigmoid) {
    const Matrix& s = cache.activations.back();
    delta = (delta.array() * s.array() * (T(1) - s.array())).matrix();
  } else if (config_.output_activation == OutputActivation::kRelu) {
    delta = (cache.activations.back().array() > T(0)).select(delta, T(0));
  }
  for (size_t i = layers_.size(); i-- > 0;) {
    const Layer& layer = layers_[i];
    const Matrix& layer_input = cache.activations[i];
    Eigen::Map<Matrix> d_weight(d_params + layer.weight_offset, layer.outputs, layer.inputs);
    Eigen::Map<Eigen::Matrix<T, Eigen::Dynamic, 1>> d_bias(d_params + layer.bias_offset, layer.outputs);
    d_weight.noalias() += delta * layer_input.transpose();
    // Column by column: a fixed summation order (Eigen's vectorised reductions depend on memory alignment,
    // which would make training runs differ).
    for (Eigen::Index j = 0; j < delta.cols(); ++j) d_bias += delta.col(j);
    if (i == 0 && d_input == nullptr) break;
    const Eigen::Map<const Matrix> weight(params_.data() + layer.weight_offset, layer.outputs, layer.inputs);
    Matrix previous = weight.transpose() * delta;
    if (i > 0) {
      // ReLU: the gradient passes where the activation was positive.
      previous = (layer_input.array() > T(0)).select(previous, T(0));
    }
    delta = std::move(previous);
  }
  if (d_input != nullptr) *d_input = std::move(delta);
}

template class Mlp<float>;
template class Mlp<double>;

}  // namespace p2n
