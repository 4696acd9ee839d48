#pragma once
// A camera for the tests that need one of a given size.

#include "nerf/camera.h"

namespace p2n::testing {

// `width` x `height` pixels, focal length `focal` pixels, the principal point at the centre; at the origin looking
// down -z until its pose is set.
inline PinholeCamera CentredCamera(int width, int height, double focal) {
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = focal;
  camera.cx = width / 2.0;
  camera.cy = height / 2.0;
  return camera;
}

}  // namespace p2n::testing
