#pragma once
// The frame the stages' files are written in: COLMAP's world (or the dataset's), undoing the poses stage's
// normalisation (applied_transform in transforms.json), or the normalised training frame itself.

#include <Eigen/Core>

#include <cmath>

#include <filesystem>
#include <string>

#include "base/enum_names.h"
#include "formats/dataset_import.h"

namespace p2n {

// Which frame: COLMAP's world or the dataset's (source), or the training frame (normalized).
enum class FrameKind { kSource, kNormalized };
template <>
struct EnumNames<FrameKind> {
  static constexpr std::pair<FrameKind, const char*> kValues[] = {{FrameKind::kSource, "source"},
                                                                  {FrameKind::kNormalized, "normalized"}};
};

// The similarity from the normalised frame to the one the files are written in.
struct OutputFrame {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // out_from_normalized, scaled
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  FrameKind kind = FrameKind::kNormalized;
  std::string description;

  Eigen::Vector3f Point(const Eigen::Vector3f& p) const;
  Eigen::Vector3f Direction(const Eigen::Vector3f& d) const;
  double Scale() const { return std::cbrt(rotation.determinant()); }
  // A camera's world_from_cam (OpenGL axes) in this frame: its centre mapped, its axes turned.
  Eigen::Matrix4d Pose(const Eigen::Matrix4d& world_from_cam) const;
  // A camera in this frame: its pose mapped, its near and far scaled.
  CameraView Camera(const CameraView& view) const;
};

// The frame `kind` of the poses stage's transforms.json (source: the inverse of its applied_transform, read by
// LoadTransformsJson); UserError naming the file when that cannot be inverted.
OutputFrame MakeOutputFrame(FrameKind kind, const ImportedDataset& poses);

// glTF's frame for the same scene: the normalised frame (+Z up) turned so that +Y is up, at the scale of `frame`
// (metres where that is in metres), its origin the scene's centre.
OutputFrame UprightFrame(const OutputFrame& frame);

}  // namespace p2n
