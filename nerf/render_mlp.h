#pragma once
// An Mlp<float>'s forward pass for rendering: the weights packed once per pass, tiles of outputs kept in
// registers, ReLU fused into each layer's store, no copies between layers and no activations kept for a backward
// pass. Where a -march=native build has AVX-512 BF16, the products are of bfloat16 values summed in float (twice
// the multiply-adds per instruction of float; bfloat16 keeps 8 bits of each input and weight: outputs within about
// 1% of the float pass's, far below what a rendered 8-bit pixel shows); with AVX2 and FMA they are float
// multiply-adds, the float pass's numbers up to the order of the sums. Training, its gradients and the occupancy
// grid use Mlp's own pass.

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "nerf/mlp.h"

namespace p2n {

class RenderMlp {
 public:
  // What this build computes with: "AVX-512 BF16", "AVX2" or nullptr (neither: use Mlp's pass).
  static const char* Instructions();
  static bool Available() { return Instructions() != nullptr; }
  // Whether the products round their inputs (bfloat16).
  static bool Rounds();

  // Packs `mlp`'s weights; std::logic_error when !Available().
  explicit RenderMlp(const Mlp<float>& mlp);

  // output (outputs x n) = the network at input (inputs x n), both column-major.
  void Forward(const float* input, Eigen::Index n, float* output) const;

 private:
  struct Layer {
    int inputs, outputs;
    int groups, row_blocks;  // input groups (of the values one broadcast holds), output blocks of a register's rows
    std::vector<uint32_t> words;  // [group][row (row_blocks * lanes)]: a group of inputs' weights in one word
    std::vector<float> bias;      // row_blocks * lanes
  };
  std::vector<Layer> layers_;
  OutputActivation output_activation_;
};

}  // namespace p2n
