#pragma once
// A synthetic scene with exact ground truth: textured objects (spheres, boxes) on a textured ground, ray-cast
// from known pinhole cameras. The textures are solid (a function of the 3D point), so a surface point looks
// the same from every view and SIFT finds plenty of features. Used by the demo and by tests.
//
// World: z up, ground at z = 0, objects around the origin. Cameras: OpenGL axes (x right, y up, looking down
// -z), pixel (i, j)'s centre at (i + 0.5, j + 0.5), as in transforms.json.

#include <OpenImageIO/imagebuf.h>
#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "base/camera.h"

namespace p2n {

struct SyntheticSceneOptions {
  std::string path = "orbit";  // "orbit": an upward spiral around the scene; "handheld": a walk along an arc
                               // in front of it with jittered position, aim and roll; "survey": rows over the
                               // ground looking ahead and down, each view seeing a small part (a large scene)
  uint64_t seed = 1;           // the handheld path's jitter
  int num_views = 24;          // cameras
  int width = 320;             // pixels
  int height = 240;            // pixels
  double fov_x_deg = 55;       // horizontal field of view, degrees
  double radius = 4.5;         // distance of the cameras from the scene centre, scene units
  double min_elevation_deg = 20;
  double max_elevation_deg = 45;
  int supersampling = 2;  // samples per pixel along each axis (anti-aliasing)
};

// A camera at `position` looking at `target` with world +z as up.
PinholeCamera LookAtCamera(const Eigen::Vector3d& position, const Eigen::Vector3d& target, int width, int height,
                           double fov_x_deg);
// The cameras of the scene along options.path; std::invalid_argument for an unknown path.
std::vector<PinholeCamera> SyntheticCameras(const SyntheticSceneOptions& options);
// Renders one view (RGB, 8 bits), in parallel over rows.
OIIO::ImageBuf RenderSyntheticView(const PinholeCamera& camera, int supersampling);
// The scene's signed distance at `point`: to the nearest surface of its spheres, boxes and ground square (the
// ground a slab of no thickness), negative inside a sphere or box. Its gradient is the surfaces' outward normal.
double SyntheticSignedDistance(const Eigen::Vector3d& point);
// Points about `spacing` apart over every surface a camera can see: the spheres above the ground, the boxes' sides
// and tops, and the ground outside the boxes.
std::vector<Eigen::Vector3d> SyntheticSurfacePoints(double spacing);
// Writes view_000.png ... and ground_truth_cameras.json (transforms.json layout, camera_angle_x, fl_x, fl_y,
// cx, cy, w, h, frames with file_path and transform_matrix) into `folder`. Throws std::runtime_error naming
// the file when a write fails.
void WriteSyntheticScene(const SyntheticSceneOptions& options, const std::filesystem::path& folder);

}  // namespace p2n
