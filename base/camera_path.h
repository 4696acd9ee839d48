#pragma once
// Camera paths for rendering new views of a scene in its normalised frame (centred on what the cameras look
// at, +z up): an orbit around the centre, and a spiral in front of the capture for scenes photographed from one
// side (LLFF-style captures).

#include <vector>

#include "base/camera.h"

namespace p2n {

struct CameraPathOptions {
  int frames = 60;
  double elevation_deg = 30;  // orbit: height above the horizontal plane through the centre
  double radius = 3;          // orbit: distance from the centre; spiral: amplitude as a multiple of the cameras' spread
  // orbit: the azimuths covered (degrees about +z from +x): from start_deg through sweep_deg; 360 goes round once,
  // less goes there and back (easing at the ends, so that the video loops; frame frames - i repeats frame i).
  double start_deg = 0;
  double sweep_deg = 360;
};

// `frames` cameras with the intrinsics of `reference` on a circle about the z axis through the origin, all
// looking at the origin; frame 0 is at azimuth start_deg.
std::vector<PinholeCamera> OrbitPath(const PinholeCamera& reference, const CameraPathOptions& options);

// For each camera, the index of the first one equal to it (size, intrinsics and pose exactly): a path's repeats.
std::vector<size_t> FirstOfEqualCameras(const std::vector<PinholeCamera>& cameras);

// The arc of azimuths (about the z axis) where `cameras` stand: from the camera after the widest gap between
// neighbours round to the one before it. When no gap is wider than `max_gap_deg`, the cameras surround the centre:
// start 0, sweep 360.
void CapturedArc(const std::vector<PinholeCamera>& cameras, double max_gap_deg, double* start_deg, double* sweep_deg);

// `frames` cameras with the intrinsics of `reference` moving on an elliptical spiral (two turns, moving in and
// out along the viewing direction) around the mean of `cameras`' positions, in the plane of their mean image
// axes, all looking at the point the mean camera looks at, `focus_distance` along its viewing direction. The
// ellipse's half-axes are options.radius times the cameras' spread (standard deviation) along those axes.
std::vector<PinholeCamera> SpiralPath(const std::vector<PinholeCamera>& cameras, const PinholeCamera& reference,
                                      double focus_distance, const CameraPathOptions& options);

// Where a set of cameras sits: the mean distance from the origin and the mean elevation (degrees above the
// z = 0 plane), the defaults of an orbit that matches the capture.
void MeanCameraPlacement(const std::vector<PinholeCamera>& cameras, double* radius, double* elevation_deg);

}  // namespace p2n
