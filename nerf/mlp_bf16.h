#pragma once
// An Mlp<float>'s forward pass for rendering, with bfloat16 products summed in float (AVX-512 BF16: twice the
// multiply-adds per instruction of float, the weights packed once per pass, no copies between layers). bfloat16
// keeps 8 bits of each input and weight: outputs within about 1% of the float pass's, far below what a rendered
// 8-bit pixel shows. Training, its gradients and the occupancy grid stay in float.

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "nerf/mlp.h"

namespace p2n {

class Bf16Mlp {
 public:
  // Whether this build has the instructions (AVX-512 BF16 and -march=native on a CPU with them).
  static bool Available();

  // Packs `mlp`'s weights; std::logic_error when !Available().
  explicit Bf16Mlp(const Mlp<float>& mlp);

  // output (outputs x n) = the network at input (inputs x n), both column-major.
  void Forward(const float* input, Eigen::Index n, float* output) const;

 private:
  struct Layer {
    int inputs, outputs;            // as the float network's
    int pairs, row_blocks;          // input pairs (inputs rounded up to even / 2), output blocks of 16 rows
    std::vector<uint16_t> weights;  // [pair][row (row_blocks * 16)][2]: a pair of inputs' weights side by side
    std::vector<float> bias;        // row_blocks * 16
  };
  std::vector<Layer> layers_;
  OutputActivation output_activation_;
};

}  // namespace p2n
