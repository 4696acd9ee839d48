#pragma once
// Gaussians in Niantic's SPZ (version 3, the one SPZ readers load: the reference library, splat-transform, Spark,
// Babylon.js), about a tenth of the standard PLY. One gzip stream: a 16-byte header (magic "NGSP", version,
// count, SH degree, the positions' fractional bits, flags), then each attribute for every splat in turn:
// positions as 24-bit fixed point, opacities (after the sigmoid) in a byte, base colours as 0.5 + 0.15 f_dc in a
// byte, log-scales as (s + 10) * 16 in a byte, rotations as the three smallest quaternion components (x, y, z, w
// order) in 10 bits each after 2 bits naming the largest, and the higher SH coefficients in a byte each (128 + 128
// c, all 8 bits: the reference writer's 5 and 4 shrink the file but dim the view-dependent colour, see
// docs/benchmarks.md), coefficient by coefficient with R, G, B together.
// SPZ's axes are right, up, back; the splat PLY's right, down, forward: y and z change sign on the way.

#include <string>
#include <vector>

#include "splat/gaussians.h"

namespace p2n {

// The file's bytes.
std::vector<char> SpzBytes(const Gaussians<float>& gaussians);

// Reads versions 2 and 3 (the rotations in 3 bytes or in 4); `name` is what errors call it. std::runtime_error
// naming it and the problem (not gzip, not SPZ, another version, a truncated body). Opacities of 0 and 255 read
// as those of 0.5 and 254.5, so that every logit is finite.
Gaussians<float> ParseSpz(const std::string& bytes, const std::string& name);

}  // namespace p2n
