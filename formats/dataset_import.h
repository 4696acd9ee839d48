#pragma once
// Datasets that already have cameras, read as they are: instant-ngp / nerfstudio (transforms.json), Blender /
// nerf_synthetic (transforms_{train,val,test}.json), LLFF (poses_bounds.npy), a COLMAP project (images/ +
// sparse/), and the course layout (.npz with images_train, c2ws_train, images_val, c2ws_val, focal). Every
// loader validates: finite numbers, orthonormal rotations, positive focal lengths, image paths inside the
// dataset (others are refused).

#include <OpenImageIO/imagebuf.h>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "formats/transforms_json.h"

namespace p2n {

struct ImportedView {
  CameraView view;               // world_from_cam and intrinsics in the dataset's world
  std::string name;              // the image's file name in the stage's images/
  std::filesystem::path source;  // the image file, or empty when `pixels` holds the image
  OIIO::ImageBuf pixels;         // the image, for datasets that store pixels (.npz)
  std::filesystem::path mask;    // its foreground mask (image_masks.h), or empty
};

struct ImportedDataset {
  DatasetKind kind = DatasetKind::kTransformsJson;
  std::vector<ImportedView> views;
  std::vector<Eigen::Vector3d> points;  // sparse points, when the dataset has them
  std::vector<std::array<uint8_t, 3>> colours;
  // Their tracks, when the dataset has them: each point's reprojection error (pixels), each view's points.
  std::vector<float> point_errors;
  std::vector<std::vector<uint32_t>> view_points;  // empty, or one list a view
  std::vector<std::filesystem::path> files;        // every file the result depends on (for the cache key)
  std::vector<std::string> warnings;
  TransformsMeta meta;  // transforms.json's own fields (LoadTransformsJson); the defaults for other datasets

  std::vector<PinholeCamera> Cameras() const;  // every view's, in order
};

// The kind of dataset at `input`; none for a plain photo folder.
std::optional<DatasetKind> DetectDataset(const std::filesystem::path& input);
// Reads the cameras (not the pixels of image files) of a dataset; UserError naming the file and field.
ImportedDataset LoadDataset(const std::filesystem::path& input);
// One transforms.json (with its frames' split, near and far and its meta fields) whose image paths must stay
// inside `root`: a workspace reads its poses stage's file with root = the workspace.
ImportedDataset LoadTransformsJson(const std::filesystem::path& file, const std::filesystem::path& root);

}  // namespace p2n
