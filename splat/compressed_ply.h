#pragma once
// Gaussians in PlayCanvas's compressed splat PLY, about a quarter of the standard layout's size at SH degree 3
// (61 bytes a splat instead of 248) and read by SuperSplat, Spark, the PlayCanvas engine and splat-transform.
// Splats go in chunks of 256, sorted along a Morton curve so that each chunk is small; a chunk stores the bounds
// of its positions, log-scales and base colours (element "chunk", 18 floats), a splat its position and log-scales
// as 11-10-11-bit fractions of those bounds, its rotation as the three smallest quaternion components in 10 bits
// each (2 bits name the largest), its base colour and opacity in 8 bits each (element "vertex", 4 uints), and the
// higher SH coefficients in 8 bits each over [-4, 4] (element "sh", in the standard f_rest order).

#include <vector>

#include "splat/gaussians.h"

namespace p2n {

inline constexpr int kCompressedChunkSize = 256;

// The file's bytes.
std::vector<char> CompressedSplatPlyBytes(const Gaussians<float>& gaussians);

}  // namespace p2n
