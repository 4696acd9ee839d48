#pragma once
// A forward-facing scene (every camera on one side looking the same way, as in LLFF captures) is learnt in the
// normalised device coordinates (NDC) of a reference camera, as the NeRF paper does for such scenes. A point at
// depth d in front of the reference camera (d from its near plane to infinity) has
//   x' = x / (d tan_x),  y' = y / (d tan_y),  z' = 1 - 2 near / d  (camera axes, OpenGL),
// so the cube [-1, 1]^3 holds everything the training cameras see out to infinity, and samples even in z' are
// even in disparity: dense near the cameras and sparse far off, as the pixels' footprints are. A straight ray
// stays straight in NDC (the map is projective): from where it crosses the near plane to its point at infinity.

#include <Eigen/Core>

#include <vector>

#include <nlohmann/json.hpp>

#include "base/camera.h"
#include "nerf/rays.h"

namespace p2n {

struct ForwardFrame {
  Eigen::Matrix3d cam_from_world = Eigen::Matrix3d::Identity();  // the reference camera's axes (OpenGL)
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();              // the reference camera's centre
  double near = 1;                                               // depth of the near plane, world units (> 0)
  double tan_x = 1, tan_y = 1;  // the cube's half-width and half-height as slopes x / d and y / d (> 0)
};

// The NDC of a world point; a point at or behind the reference camera's plane goes to z' = -2 (outside the cube).
Eigen::Vector3d ForwardNdc(const ForwardFrame& frame, const Eigen::Vector3d& world);
// d(ForwardNdc)/d(world) at `world`; zero at or behind the reference camera's plane.
Eigen::Matrix3d ForwardNdcJacobian(const ForwardFrame& frame, const Eigen::Vector3d& world);

// A world ray in NDC: the segment from `start` (where the ray is first at least `near` deep) to `end` (its point at
// infinity), and the map between the fraction s in [0, 1) of that segment and the distance t along the world ray.
struct ForwardRay {
  bool valid = false;  // false: the ray never gets deeper (it runs parallel to or back towards the camera plane)
  Eigen::Vector3d start, end;
  double t0 = 0, depth0 = 1, depth_rate = 1;  // at start: world distance and depth; depth gained per world unit

  double Distance(double s) const { return t0 + depth0 * s / ((1 - s) * depth_rate); }
  double Fraction(double t) const { return 1 - depth0 / (depth0 + (t - t0) * depth_rate); }
  // The NDC distance from `start` of the point at world distance t.
  double NdcDistance(double t) const { return (end - start).norm() * Fraction(t); }
};
ForwardRay ToForward(const ForwardFrame& frame, const Ray& ray);

// Whether `cameras` were taken from one side looking one way, as LLFF captures are: every viewing direction within
// `max_angle_deg` of their mean. The default, 15, takes photos looking inwards from an arc of up to about 30
// degrees (fern's are within 9.5 of their mean, fox's within 52).
bool FacesForward(const std::vector<PinholeCamera>& cameras, double max_angle_deg = 15);

// The frame for a set of training cameras: centred at their mean centre, looking along their mean viewing
// direction, upright by their mean up vector; the near plane at 0.8 x the nearest scene depth seen (`nears`, per
// camera, <= 0: unknown; none known: a tenth of the cameras' distance from the origin); tan_x and tan_y just wide
// enough for every training ray (from its corner rays at the near plane and at infinity).
// std::invalid_argument when there is no camera or no camera ray looks forward.
ForwardFrame FitForwardFrame(const std::vector<PinholeCamera>& cameras, const std::vector<double>& nears);

nlohmann::json ForwardFrameJson(const ForwardFrame& frame);
// std::invalid_argument naming the field when one is missing or out of range.
ForwardFrame ForwardFrameFromJson(const nlohmann::json& json);

}  // namespace p2n
