#pragma once
// A fully connected network on column batches: inputs are (features x batch) matrices, so every layer is one
// matrix product. Hidden layers use ReLU; the output is linear, sigmoid or ReLU. Parameters live in one flat vector
// (per layer: W, out x in, column-major; then b) so that one optimiser updates them all.
//
// Templated on the scalar: float for training (its products from mlp_kernels where the build has AVX2 and FMA,
// Eigen's otherwise), double for gradient checks.

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <vector>

namespace p2n {

enum class OutputActivation { kNone, kSigmoid, kRelu };

struct MlpConfig {
  int inputs = 0;
  int outputs = 0;
  int width = 64;         // neurons per hidden layer
  int hidden_layers = 2;  // 0: a single linear layer
  OutputActivation output_activation = OutputActivation::kNone;

  nlohmann::json ToJson() const;
};

template <typename T>
class Mlp {
 public:
  using Matrix = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;

  // Activations of every layer from one Forward(), kept for Backward().
  struct Cache {
    std::vector<Matrix> activations;  // [0] the input, then each layer's output after its activation
  };

  // Weights and biases uniform in +-1/sqrt(fan_in), as PyTorch's nn.Linear (the seed's model); deterministic
  // for a seed.
  Mlp(const MlpConfig& config, uint64_t seed);

  const MlpConfig& config() const { return config_; }
  int num_params() const { return static_cast<int>(params_.size()); }
  T* params() { return params_.data(); }
  const T* params() const { return params_.data(); }

  // output = f(input); input is (inputs x n).
  void Forward(const Matrix& input, Matrix* output, Cache* cache) const;
  // The same with the input moved into the cache and the output left there (the cache's last activation, which
  // this returns): no copy of either.
  const Matrix& Forward(Matrix input, Cache* cache) const;
  // Given dL/d(output) (outputs x n), adds dL/d(params) into `d_params` (num_params() values) and, when
  // `d_input` is not null, writes dL/d(input): its first `input_rows` rows alone when that is given (the inputs
  // with a use for their gradient first, as the colour network's geometry features before the fixed direction
  // encoding), every row when it is negative.
  void Backward(const Cache& cache, const Matrix& d_output, T* d_params, Matrix* d_input, int input_rows = -1) const;

  // Where each layer's weights (outputs x inputs, column-major) and biases are in params().
  struct Layer {
    int inputs, outputs;
    size_t weight_offset, bias_offset;
  };
  const std::vector<Layer>& layers() const { return layers_; }

 private:
  MlpConfig config_;
  std::vector<Layer> layers_;
  std::vector<T> params_;
};

extern template class Mlp<float>;
extern template class Mlp<double>;

}  // namespace p2n
