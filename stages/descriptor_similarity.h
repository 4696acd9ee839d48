#pragma once
// The dot products of SIFT descriptors (bytes) of one image with those of another, exactly, as floats (integers
// below 2^24). With AVX-512 VNNI (a -march=native build on a CPU that has it) as byte products summed four at a
// time into 32-bit lanes: four times the multiply-adds per instruction of a float matrix product, the same
// numbers; elsewhere as a float matrix product.

#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "formats/colmap_database.h"

namespace p2n {

class DescriptorSimilarity {
 public:
  // Keeps `a` (its rows of the products: a's descriptors) in the layout the products read.
  explicit DescriptorSimilarity(const SiftDescriptors& a);

  // Column stride of Block()'s output: a.cols() rounded up.
  Eigen::Index stride() const { return stride_; }
  // out[j * stride() + i] = a_i . b_(first + j) for i < a.cols(), j < width (the padding rows are written too).
  void Block(const SiftDescriptors& b, Eigen::Index first, Eigen::Index width, float* out) const;

  // Whether Block() uses VNNI in this build.
  static bool UsesVnni();

 private:
  Eigen::Index rows_, stride_;
  std::vector<uint8_t> packed_;    // VNNI: per 16 rows, per 4 of the 128 dimensions, 16 x 4 bytes
  std::vector<int32_t> row_bias_;  // VNNI: 128 times each row's sum (the products read b - 128, signed)
  Eigen::MatrixXf a_float_;        // otherwise
};

}  // namespace p2n
