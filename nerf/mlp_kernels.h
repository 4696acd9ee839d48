#pragma once
// The three matrix products of a fully connected layer's training passes, in float with AVX2 and FMA, for Mlp<float>
// (whose numbers they are up to the order of the sums). A layer is small (at most a few hundred by a few hundred)
// and the batch long, the shape where a general GEMM spends much of its time packing its operands on every call:
// here the weights are packed once a call into panels of 8-row blocks, and tiles of 16 rows by 6 samples (or
// inputs) stay in registers through the whole sum, with the bias, ReLU or the ReLU mask of the backward pass
// applied as a tile is stored. Each sum runs in a fixed order, so results do not depend on threads or alignment.
// Columns are samples throughout: every matrix is column-major, (features x samples).

#include <Eigen/Core>

namespace p2n::mlp_kernels {

// Whether this build has the kernels (AVX2 and FMA); without them Mlp uses Eigen's products.
bool Available();

// y (m x n) = W x + b, then max(0, .) where `relu`; W is (m x k), b (m), x (k x n).
void LayerForward(const float* weight, const float* bias, int m, int k, const float* x, Eigen::Index n, bool relu,
                  float* y);

// dx (k x n) = W^T dy, zero wherever `mask` (k x n, the layer's input) is not positive; no mask: nothing zeroed.
void LayerInputGradient(const float* weight, int m, int k, const float* dy, Eigen::Index n, const float* mask,
                        float* dx);

// d_weight (m x k) += dy x^T and d_bias (m) += the sum of dy's columns, samples summed in order.
void AddLayerGradient(const float* dy, int m, const float* x, int k, Eigen::Index n, float* d_weight, float* d_bias);

}  // namespace p2n::mlp_kernels
