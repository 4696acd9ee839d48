#include "formats/output_frame.h"

#include <Eigen/Geometry>

#include <cmath>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"

namespace p2n {

namespace fs = std::filesystem;

Eigen::Vector3f OutputFrame::Point(const Eigen::Vector3f& p) const {
  return (rotation * p.cast<double>() + translation).cast<float>();
}

Eigen::Vector3f OutputFrame::Direction(const Eigen::Vector3f& d) const {
  return (rotation * d.cast<double>()).normalized().cast<float>();
}

Eigen::Matrix4d OutputFrame::Pose(const Eigen::Matrix4d& world_from_cam) const {
  Eigen::Matrix4d out = world_from_cam;
  out.topLeftCorner<3, 3>() = rotation / Scale() * world_from_cam.topLeftCorner<3, 3>();
  out.topRightCorner<3, 1>() = rotation * world_from_cam.topRightCorner<3, 1>() + translation;
  return out;
}

CameraView OutputFrame::Camera(const CameraView& view) const {
  CameraView out = view;
  const double scale = Scale();
  out.camera.world_from_cam = Pose(view.camera.world_from_cam);
  if (view.near > 0) out.near = view.near * scale;
  if (view.far > 0) out.far = view.far * scale;
  return out;
}

OutputFrame MakeOutputFrame(FrameKind kind, const ImportedDataset& poses) {
  OutputFrame out;
  out.kind = kind;
  if (kind == FrameKind::kNormalized) {
    out.description = "frame: normalized (the training frame of 20_poses/transforms.json)";
    return out;
  }
  const Eigen::Matrix4d source_from_normalized = poses.meta.normalization.normalized_from_world.inverse();
  if (!source_from_normalized.allFinite()) {  // files.front(): the transforms.json
    throw UserError(
        format("'{}': applied_transform cannot be inverted; rerun the poses stage", poses.files.front().string()));
  }
  out.rotation = source_from_normalized.topLeftCorner<3, 3>();
  out.translation = source_from_normalized.topRightCorner<3, 1>();
  out.description =
      "frame: source (COLMAP's world, or the dataset's: the inverse of applied_transform in 20_poses/transforms.json)";
  return out;
}

OutputFrame UprightFrame(const OutputFrame& frame) {
  OutputFrame out;
  out.kind = frame.kind;
  out.rotation << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  out.rotation *= frame.Scale();
  out.description = "frame: upright (glTF's: +Y up, the normalised frame turned, at the scale of the " +
                    std::string(EnumName(frame.kind)) + " frame, centred on the scene)";
  return out;
}

}  // namespace p2n
