#include "stages/poses_stage.h"

#include <algorithm>
#include <cmath>

#include "nerf/camera.h"
#include "pipeline/errors.h"
#include "pipeline/file_util.h"
#include "pipeline/format.h"
#include "pipeline/log.h"
#include "stages/colmap_model.h"
#include "stages/ply.h"
#include "stages/scene_normalization.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr size_t kMinPointsForBounds = 8;
constexpr double kNearMargin = 0.8, kFarMargin = 1.2;

nlohmann::json MatrixJson(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

double Quantile(std::vector<double> values, double q) {
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * (values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

// Pinhole intrinsics of an undistorted COLMAP camera.
nlohmann::json Intrinsics(const ColmapCamera& camera) {
  double fx, fy, cx, cy;
  if (camera.model == "PINHOLE") {
    fx = camera.params[0], fy = camera.params[1], cx = camera.params[2], cy = camera.params[3];
  } else if (camera.model == "SIMPLE_PINHOLE") {
    fx = fy = camera.params[0], cx = camera.params[1], cy = camera.params[2];
  } else {
    throw UserError(format("camera {} is a {} camera; the poses stage reads undistorted (pinhole) models",
                           camera.id, camera.model));
  }
  return {{"camera_model", "PINHOLE"}, {"fl_x", fx}, {"fl_y", fy}, {"cx", cx}, {"cy", cy},
          {"w", camera.width}, {"h", camera.height},
          {"camera_angle_x", 2 * std::atan(camera.width / (2 * fx))},
          {"camera_angle_y", 2 * std::atan(camera.height / (2 * fy))}};
}

}  // namespace

void PosesOptions::Check() const {
  CheckOption(holdout_every >= 0, "poses.holdout_every", "must be 0 (none) or positive");
}

void PosesStage::Run(StageContext& context) const {
  const PosesOptions options = ReadOptions<PosesOptions>(context.config, "poses");
  const fs::path sfm = context.upstream_dirs.at("sfm");
  const fs::path model_dir = sfm / "undistorted" / "sparse";
  const ColmapModel model = ReadColmapModel(model_dir);
  if (model.images.empty()) throw UserError(format("the model in '{}' has no registered image", model_dir.string()));

  // Cameras in COLMAP's world, sorted by image name.
  std::vector<const ColmapImage*> images;
  for (const auto& [id, image] : model.images) images.push_back(&image);
  std::sort(images.begin(), images.end(), [](const ColmapImage* a, const ColmapImage* b) { return a->name < b->name; });
  std::vector<Eigen::Matrix4d> world_from_cam;
  std::vector<Eigen::Vector3d> centres, ups, axes, points;
  for (const ColmapImage* image : images) {
    world_from_cam.push_back(WorldFromOpenGlCamera(image->cam_from_world_rotation, image->cam_from_world_translation));
    centres.push_back(world_from_cam.back().topRightCorner<3, 1>());
    ups.push_back(world_from_cam.back().block<3, 1>(0, 1));     // OpenGL +y
    axes.push_back(-world_from_cam.back().block<3, 1>(0, 2));   // OpenGL cameras look down -z
  }
  for (const auto& [id, point] : model.points) points.push_back(point.xyz);

  Normalization normalization;
  if (options.normalize) {
    normalization = NormalizeScene(centres, ups, axes, points);
    for (const std::string& warning : normalization.warnings) LogWarning("poses: " + warning);
  }
  const Eigen::Matrix4d& normalized_from_world = normalization.normalized_from_world;
  const double scale = normalization.scale;
  const auto to_normalized = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3d((normalized_from_world * p.homogeneous()).head<3>());
  };

  // Near/far per view from the depths of the points it sees; views with too few points use the global bounds.
  std::vector<std::vector<double>> depths(images.size());
  std::vector<double> all_depths;
  for (size_t i = 0; i < images.size(); ++i) {
    const Eigen::Matrix3d cv_from_world = images[i]->cam_from_world_rotation.toRotationMatrix();
    for (const uint64_t id : images[i]->point3d_ids) {
      const auto it = model.points.find(id);
      if (id == kNoPoint3D || it == model.points.end()) continue;
      const double z = (cv_from_world * it->second.xyz + images[i]->cam_from_world_translation).z() * scale;
      if (z > 0 && std::isfinite(z)) depths[i].push_back(z);
    }
    all_depths.insert(all_depths.end(), depths[i].begin(), depths[i].end());
  }
  double global_near = 0.05, global_far = 10.0;
  if (all_depths.size() >= kMinPointsForBounds) {
    global_near = kNearMargin * Quantile(all_depths, 0.01);
    global_far = kFarMargin * Quantile(all_depths, 0.99);
  } else {
    LogWarning("poses: too few sparse points for depth bounds; using near 0.05 and far 10 (normalised units)");
  }

  const bool one_camera = model.cameras.size() == 1;
  nlohmann::json transforms = one_camera ? Intrinsics(model.cameras.begin()->second) : nlohmann::json::object();
  nlohmann::json frames = nlohmann::json::array();
  size_t held_out = 0;
  for (size_t i = 0; i < images.size(); ++i) {
    Eigen::Matrix4d normalized_from_cam = normalized_from_world * world_from_cam[i];
    normalized_from_cam.topLeftCorner<3, 3>() /= scale;  // a rotation again: the scale applies to positions only
    const bool holdout = options.holdout_every > 0 && i % options.holdout_every == 0;
    held_out += holdout;
    const bool own_bounds = depths[i].size() >= kMinPointsForBounds;
    nlohmann::json frame = {
        {"file_path", "../10_sfm/undistorted/images/" + images[i]->name},
        {"transform_matrix", MatrixJson(normalized_from_cam)},
        {"split", holdout ? "val" : "train"},
        {"near", own_bounds ? kNearMargin * Quantile(depths[i], 0.01) : global_near},
        {"far", own_bounds ? kFarMargin * Quantile(depths[i], 0.99) : global_far},
        {"colmap_image_id", images[i]->id}};
    if (!one_camera) frame.update(Intrinsics(model.cameras.at(images[i]->camera_id)));
    frames.push_back(frame);
  }
  transforms["frames"] = frames;
  transforms["aabb_scale"] = 1;
  transforms["applied_transform"] = MatrixJson(normalized_from_world.topRows<3>());
  transforms["applied_scale"] = scale;
  transforms["normalization"] = {{"centre_from", normalization.centre_from}, {"up_from", normalization.up_from}};
  transforms["near"] = global_near;
  transforms["far"] = global_far;
  WriteJsonAtomic(context.output_dir / "transforms.json", transforms);

  std::vector<ColouredPoint> cloud;
  for (const auto& [id, point] : model.points) cloud.push_back({to_normalized(point.xyz).cast<float>(), point.rgb});
  WritePly(context.output_dir / "sparse_points.ply", cloud);
  context.summary = {{"views", images.size()}, {"held_out", held_out}, {"points", cloud.size()}};
  LogInfo(format("poses: {} views ({} held out), scene scale {:.4g} (centre from {}, up from {})", images.size(),
                 held_out, scale, normalization.centre_from, normalization.up_from));
}

}  // namespace p2n
