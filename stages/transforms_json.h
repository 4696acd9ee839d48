#pragma once
// transforms.json, the cameras the NeRF trains from, in the layout instant-ngp and nerfstudio read: intrinsics
// (fl_x, fl_y, cx, cy, w, h) at the top level when every view shares them, else per frame; frames with
// file_path and transform_matrix (camera-to-world, OpenGL axes). Our extras: split, near, far per frame, and
// applied_transform (3x4, normalised from the source world) with applied_scale.

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "nerf/camera.h"
#include "stages/scene_normalization.h"

namespace p2n {

struct CameraView {
  std::string file_path;  // as written in transforms.json, relative to it
  PinholeCamera camera;   // intrinsics and world_from_cam (OpenGL axes) in the source world
  std::string split = "train";
  double near = -1, far = -1;  // in source-world units along the view; negative: unknown
};

// Normalises the views (when `normalize`) from their cameras and `points`, fills unknown near/far from the
// unit cube, and writes transforms.json. `extra` is merged into the top level.
void WriteTransformsJson(const std::filesystem::path& path, const std::vector<CameraView>& views,
                         const Normalization& normalization, const nlohmann::json& extra);

// Marks every Nth view (0: none) as "val", the others "train"; views whose split is already "val" or "test"
// keep it.
void AssignHoldout(std::vector<CameraView>* views, int every);

// Centres, ups and viewing directions of the views, for NormalizeScene.
void CameraFrames(const std::vector<CameraView>& views, std::vector<Eigen::Vector3d>* centres,
                  std::vector<Eigen::Vector3d>* ups, std::vector<Eigen::Vector3d>* axes);

}  // namespace p2n
