#pragma once
// A ray's segments as the volume rendering and distortion loss tests build them: densities, colours, midpoints and
// lengths in double precision.

#include <vector>

#include "nerf/volume_rendering.h"

namespace p2n::testing {

struct SegmentRay {
  std::vector<double> sigma, rgb, t, delta;
  RaySegments<double> segments() const { return {sigma.data(), rgb.data(), t.data(), delta.data(), sigma.size()}; }
};

}  // namespace p2n::testing
