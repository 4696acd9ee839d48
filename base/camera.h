#pragma once
// Pinhole cameras and the one place where camera axis conventions change (docs/design.md §3).
//
// COLMAP / OpenCV camera: x right, y down, z forward. NeRF / OpenGL / Blender camera (transforms.json): x right,
// y up, looking down -z. Pixel (i, j)'s centre is at (i + 0.5, j + 0.5) in both. Transforms are named
// target_from_source.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace p2n {

struct PinholeCamera {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;                         // pixels
  Eigen::Matrix4d world_from_cam = Eigen::Matrix4d::Identity();  // OpenGL camera axes
};

// The same camera with images `width` pixels wide (the height by the aspect ratio, at least 1), intrinsics scaled.
PinholeCamera ScaledCamera(const PinholeCamera& camera, int width);
// The same camera with its images resized to `width` x `height`: the intrinsics scaled along each axis (the image's
// edges stay where they were, as an area or linear resize keeps them).
PinholeCamera ResizedCamera(const PinholeCamera& camera, int width, int height);

// Maps points in OpenCV camera axes to OpenGL camera axes (flips y and z); its inverse is the paired
// OpenCvFromOpenGlCamera() (the same matrix: the flip is its own inverse).
Eigen::Matrix3d OpenGlFromOpenCvCamera();
Eigen::Matrix3d OpenCvFromOpenGlCamera();

// world_from_cam in OpenGL camera axes from COLMAP's cam_from_world (OpenCV axes), and back.
Eigen::Matrix4d WorldFromOpenGlCamera(const Eigen::Quaterniond& cam_from_world_rotation,
                                      const Eigen::Vector3d& cam_from_world_translation);
void OpenCvCamFromWorld(const Eigen::Matrix4d& world_from_gl_cam, Eigen::Quaterniond* cam_from_world_rotation,
                        Eigen::Vector3d* cam_from_world_translation);

// world_from_cam (OpenGL axes) of a camera at `position` looking at `target`, level (its x axis horizontal) with
// world +z as up; looking straight up or down, world +y is up in the image instead.
Eigen::Matrix4d LookAtPose(const Eigen::Vector3d& position, const Eigen::Vector3d& target);

// The pixel where `point_in_world` appears; its depth along the viewing direction in `depth` (negative:
// behind the camera).
Eigen::Vector2d Project(const PinholeCamera& camera, const Eigen::Vector3d& point_in_world, double* depth = nullptr);

// The indices (ascending) of `count` of `cameras` spread over where they stand and which way they look: farthest-point
// sampling, from the first camera, on each camera's centre (in units of the centres' root-mean-square distance from
// their mean) and viewing direction (a unit vector); every index when there are no more than `count`, fewer when the
// others coincide with chosen ones.
std::vector<size_t> SpreadCameras(const std::vector<PinholeCamera>& cameras, size_t count);

}  // namespace p2n
