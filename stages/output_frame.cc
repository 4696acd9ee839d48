#include "stages/output_frame.h"

#include <Eigen/Geometry>

#include <cmath>

#include "pipeline/errors.h"
#include "pipeline/file_util.h"
#include "pipeline/format.h"

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

// applied_transform (normalised_from_source, 3x4) of transforms.json, inverted when the source frame is asked for.
OutputFrame MakeOutputFrame(const std::string& frame, const fs::path& transforms) {
  OutputFrame out;
  out.name = frame;
  if (frame == "normalized") {
    out.description = "frame: normalized (the training frame of 20_poses/transforms.json)";
    return out;
  }
  const nlohmann::json json = ReadJsonFile(transforms);
  Eigen::Matrix4d normalized_from_source = Eigen::Matrix4d::Identity();
  if (json.contains("applied_transform")) {
    const nlohmann::json& a = json["applied_transform"];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) normalized_from_source(r, c) = a.at(r).at(c).get<double>();
    }
  }
  const Eigen::Matrix4d source_from_normalized = normalized_from_source.inverse();
  if (!source_from_normalized.allFinite()) {
    throw UserError(format("'{}': applied_transform cannot be inverted; rerun the poses stage", transforms.string()));
  }
  out.rotation = source_from_normalized.topLeftCorner<3, 3>();
  out.translation = source_from_normalized.topRightCorner<3, 1>();
  out.description =
      "frame: source (COLMAP's world, or the dataset's: the inverse of applied_transform in 20_poses/transforms.json)";
  return out;
}

}  // namespace p2n
