#pragma once
// Gaussians as glTF 2.0 binary with Khronos's KHR_gaussian_splatting (its 2025 review draft): one point primitive
// whose POSITION, KHR_gaussian_splatting:ROTATION (x, y, z, w), :SCALE (natural log), :OPACITY (after the
// sigmoid) and :SH_DEGREE_l_COEF_n (RGB; n = 0..2l, m = -l..l) hold the splats as they are (floats), and COLOR_0
// their base colour and opacity (a byte each) for viewers that only draw points. The extension's kernel is "ellipse",
// its colour space "srgb_rec709_display" (the photos' own), sorting "cameraDistance", projection "perspective". The
// splats are written in whatever frame they are in; glTF's is +Y up.

#include <string>

#include "splat/gaussians.h"

namespace p2n {

// The file's bytes; `generator` names what wrote it.
std::string SplatGlbBytes(const Gaussians<float>& gaussians, const std::string& generator);

// Reads what SplatGlbBytes writes (float attributes, SH up to degree 3); `name` is what errors call it.
// std::runtime_error naming it and the problem (not glTF, no KHR_gaussian_splatting primitive, a missing or
// malformed attribute).
Gaussians<float> ParseSplatGlb(const std::string& bytes, const std::string& name);

}  // namespace p2n
