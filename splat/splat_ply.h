#pragma once
// Gaussians in the standard 3D Gaussian Splatting PLY (what SuperSplat, the PlayCanvas and three.js viewers and
// the splat plug-ins read): binary little-endian float vertices x y z nx ny nz f_dc_0..2 f_rest_0..N opacity
// scale_0..2 rot_0..3. f_rest holds the higher coefficients channel by channel (all of red's, then green's,
// then blue's); opacity is a logit, scales natural logarithms, rot (w, x, y, z); normals are written as zero.

#include <filesystem>
#include <string>
#include <vector>

#include "splat/gaussians.h"

namespace p2n {

// The file's bytes; `comments` go into the header, one line each.
std::vector<char> SplatPlyBytes(const Gaussians<float>& gaussians, const std::vector<std::string>& comments = {});
// Writes SplatPlyBytes atomically; std::runtime_error naming the file when it cannot.
void WriteSplatPly(const std::filesystem::path& path, const Gaussians<float>& gaussians,
                   const std::vector<std::string>& comments = {});

// Reads a standard splat PLY (properties in any order, float or double; others ignored; the SH degree from the
// count of f_rest properties). `name` is what errors call it. std::runtime_error naming it and the problem
// (the format, a missing property, a truncated body).
Gaussians<float> ParseSplatPly(const std::string& bytes, const std::string& name);
Gaussians<float> ReadSplatPly(const std::filesystem::path& path);

}  // namespace p2n
