#pragma once
// A camera for the tests that need one of a given size.

#include <cmath>
#include <vector>

#include "base/camera.h"

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

// 40 x 30 pixel cameras 2 units from the z axis, half a unit up, at these azimuths (degrees), each looking at the
// origin.
inline std::vector<PinholeCamera> RingOfCameras(const std::vector<double>& azimuths_deg) {
  std::vector<PinholeCamera> cameras;
  for (const double a : azimuths_deg) {
    PinholeCamera camera = CentredCamera(40, 30, 50);
    const double r = a * M_PI / 180;
    camera.world_from_cam = LookAtPose({2 * std::cos(r), 2 * std::sin(r), 0.5}, {0, 0, 0});
    cameras.push_back(camera);
  }
  return cameras;
}

}  // namespace p2n::testing
