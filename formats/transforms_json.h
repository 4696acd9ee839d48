#pragma once
// transforms.json, the cameras the NeRF trains from, in the layout instant-ngp and nerfstudio read: intrinsics
// (fl_x, fl_y, cx, cy, w, h) at the top level when every view shares them, else per frame; frames with
// file_path and transform_matrix (camera-to-world, OpenGL axes). Our extras: split, near, far per frame;
// applied_transform (3x4, normalised from the source world) with applied_scale and how the normalisation was
// chosen; the dataset imported and the background its images show, when known; the export's frame.
// TransformsFile is the one place that writes and reads it: the poses, import and export stages write one, every
// later stage reads the poses stage's, and the dataset importer reads instant-ngp's, nerfstudio's and Blender's.

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "base/camera.h"
#include "base/enum_names.h"
#include "formats/scene_normalization.h"

namespace p2n {

// The kinds of dataset with cameras that the import stage reads (dataset_import.h).
enum class DatasetKind { kTransformsJson, kBlender, kLlff, kColmap, kNpz };
template <>
struct EnumNames<DatasetKind> {
  static constexpr std::pair<DatasetKind, const char*> kValues[] = {{DatasetKind::kTransformsJson, "transforms.json"},
                                                                    {DatasetKind::kBlender, "blender"},
                                                                    {DatasetKind::kLlff, "llff"},
                                                                    {DatasetKind::kColmap, "colmap"},
                                                                    {DatasetKind::kNpz, "npz"}};
};

// Which part of a capture a view belongs to: trained on, held out for evaluation (a dataset's "val" or "test", or
// AssignHoldout's "val"), or left out of training (KeepTrainingViews).
enum class ViewSplit { kTrain, kVal, kTest, kUnused };
template <>
struct EnumNames<ViewSplit> {
  static constexpr std::pair<ViewSplit, const char*> kValues[] = {{ViewSplit::kTrain, "train"},
                                                                  {ViewSplit::kVal, "val"},
                                                                  {ViewSplit::kTest, "test"},
                                                                  {ViewSplit::kUnused, "unused"}};
};

struct CameraView {
  std::string file_path;  // as written in transforms.json, relative to it
  PinholeCamera camera;   // intrinsics and world_from_cam (OpenGL axes)
  ViewSplit split = ViewSplit::kTrain;
  double near = -1, far = -1;          // along the view, in the file's units; negative: unknown
  std::array<double, 4> distortion{};  // OpenCV k1, k2, p1, p2 (a dataset's; ours are undistorted: zero)
};

// The fields of transforms.json beyond its frames.
struct TransformsMeta {
  // applied_transform and applied_scale: the similarity from the source world (COLMAP's, or the dataset's) to
  // the frame of the views; centre_from and up_from: how it was chosen ("" when it was not).
  Normalization normalization;
  std::optional<DatasetKind> dataset_kind;  // the dataset imported; none for photos
  std::string dataset_path;
  // The colour behind the scene when the import knows it (the colour transparent images were composited on, or the
  // plain one every image's border shows); none: unknown, learnt from photos (white stands in).
  std::optional<std::array<float, 3>> background;
  std::string heldout_rule;      // how the held-out views were chosen (AssignHoldout); empty: by the dataset
  std::string frame;             // the export's: which frame its cameras are in; empty otherwise
  bool cameras_refined = false;  // the export's: the training cameras as camera refinement left them

  std::array<float, 3> Background() const { return background.value_or(std::array<float, 3>{1, 1, 1}); }
};

struct TransformsFile {
  std::vector<CameraView> views;
  TransformsMeta meta;
  std::vector<std::string> warnings;  // from Read: frames left out

  // Writes the views as they are (see NormalizedViews) and the meta fields.
  void Write(const std::filesystem::path& file) const;
  // Reads ours, instant-ngp's, nerfstudio's or one Blender split's (`split` for frames that name none). Image
  // paths must resolve inside `root`; frames whose image is missing are left out with a warning (instant-ngp's fox
  // lists 17); a frame without w and h takes its image's size. Every camera is checked (CheckCamera). UserError
  // naming the file and the field.
  static TransformsFile Read(const std::filesystem::path& file, const std::filesystem::path& root,
                             ViewSplit split = ViewSplit::kTrain);
  // The image of a view, resolved against the file's folder.
  static std::filesystem::path ImagePath(const std::filesystem::path& file, const CameraView& view);
};

// The views in the frame of `normalization`, with unknown near and far filled from the unit cube as each camera
// sees it.
std::vector<CameraView> NormalizedViews(const std::vector<CameraView>& views, const Normalization& normalization);

// Captures of fewer views than this hold out views inside the span of the others (AssignHoldout).
inline constexpr size_t kFewViews = 20;

// Marks views val (held out for evaluation) or train; views whose split is already val or test keep it.
// Every Nth from the first (0: none; the NeRF paper's protocol), or, with `inside_span` and fewer than kFewViews
// views, as many views spread over the sequence, each inside the span of the training cameras (OutsideSpan): with
// so few photos the ends of an arc would measure extrapolation, not new views. Returns the rule, said in words
// ("" when none is held out).
std::string AssignHoldout(std::vector<CameraView>* views, int every, bool inside_span);

// Keeps `count` of the training views (0: all), spread evenly over them in order (the first and the last among them);
// the others' split becomes unused: what a capture of fewer photos would train on, scored on the same views.
void KeepTrainingViews(std::vector<CameraView>* views, int count);

// Centres, ups and viewing directions of the views, for NormalizeScene.
void CameraFrames(const std::vector<CameraView>& views, std::vector<Eigen::Vector3d>* centres,
                  std::vector<Eigen::Vector3d>* ups, std::vector<Eigen::Vector3d>* axes);

// UserError naming `file` and `field` unless the camera is usable: a finite pose with an orthonormal rotation,
// positive finite focal lengths, an image size. Every dataset reader checks its cameras with it.
void CheckCamera(const PinholeCamera& camera, const std::filesystem::path& file, const std::string& field);

}  // namespace p2n
