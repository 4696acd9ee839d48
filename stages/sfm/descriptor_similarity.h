#pragma once
// The dot products of SIFT descriptors (bytes) of one image with those of another, exactly, as floats (integers
// below 2^24), as integer products summed into 32-bit lanes where a -march=native build has the instructions: with
// AVX-512 VNNI four byte products at a time (four times the multiply-adds per instruction of a float matrix
// product), with AVX2 two 16-bit ones; elsewhere as a float matrix product. The same numbers on every path.

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

  // What Block() computes with in this build: "AVX-512 VNNI", "AVX2" or "float".
  static const char* Instructions();

 private:
  Eigen::Index rows_, stride_;
  // Integer paths: per block of a register's lanes of rows, per group of the dimensions one 32-bit word holds (4
  // bytes, or 2 of 16 bits), a word a row; and what each row's products need added back (VNNI: 128 times its sum).
  std::vector<uint32_t> packed_;
  std::vector<int32_t> row_bias_;
  Eigen::MatrixXf a_float_;  // the float path
};

}  // namespace p2n
