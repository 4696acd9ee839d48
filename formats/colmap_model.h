#pragma once
// COLMAP sparse models (cameras, images, points3D) in COLMAP's binary and text formats, read and written by
// us (COLMAP is not called to convert). Readers validate everything and name the file and the record on error;
// counts are checked against the bytes left before anything is allocated.
//
// Conventions as in COLMAP: an image stores cam_from_world (rotation as a unit quaternion w, x, y, z, and a
// translation); the camera has OpenCV axes (x right, y down, z forward); pixel (0, 0)'s centre is (0.5, 0.5).

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "base/camera.h"

namespace p2n {

struct ColmapCamera {
  uint32_t id = 0;
  std::string model;  // SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE, ...
  uint64_t width = 0, height = 0;
  std::vector<double> params;  // in COLMAP's order for the model
};

struct ColmapImage {
  uint32_t id = 0;
  Eigen::Quaterniond cam_from_world_rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d cam_from_world_translation = Eigen::Vector3d::Zero();
  uint32_t camera_id = 0;
  std::string name;
  std::vector<Eigen::Vector2d> points2d;
  std::vector<uint64_t> point3d_ids;  // kNoPoint3D where a 2D point has no 3D point
};

inline constexpr uint64_t kNoPoint3D = ~uint64_t{0};

struct ColmapPoint3D {
  uint64_t id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  std::array<uint8_t, 3> rgb = {0, 0, 0};
  double error = 0;
  std::vector<std::pair<uint32_t, uint32_t>> track;  // (image id, index of the 2D point)
};

struct ColmapModel {
  std::map<uint32_t, ColmapCamera> cameras;
  std::map<uint32_t, ColmapImage> images;
  std::map<uint64_t, ColmapPoint3D> points;
};

// The number of parameters of a COLMAP camera model, or -1 for an unknown name; its name from its id ("" when
// unknown).
int ColmapModelParamCount(const std::string& model);
std::string ColmapModelName(int model_id);

// Pinhole intrinsics (width, height, fx, fy, cx, cy) of a COLMAP camera, and its OpenCV distortion (k1, k2,
// p1, p2; zero for pinhole models) in `distortion`. SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL and OPENCV;
// UserError naming the camera for fisheye and the other models.
PinholeCamera PinholeFromColmap(const ColmapCamera& camera, std::array<double, 4>* distortion);

// Reads the model in `folder` (binary when cameras.bin exists, else text). Throws UserError naming the file and
// the record when a file is missing, truncated or holds impossible values.
ColmapModel ReadColmapModel(const std::filesystem::path& folder);
ColmapModel ReadColmapModelBinary(const std::filesystem::path& folder);
ColmapModel ReadColmapModelText(const std::filesystem::path& folder);
// points3D.bin alone (a dataset may ship it without images.bin); UserError naming the file and the point.
std::map<uint64_t, ColmapPoint3D> ReadColmapPointsBinary(const std::filesystem::path& file);
void WriteColmapModelBinary(const ColmapModel& model, const std::filesystem::path& folder);
void WriteColmapModelText(const ColmapModel& model, const std::filesystem::path& folder);

}  // namespace p2n
