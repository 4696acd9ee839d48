#include "stages/sfm/poses_stage.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "base/camera.h"
#include "base/errors.h"
#include "base/file_util.h"
#include "base/float_image.h"
#include "base/format.h"
#include "base/image_io.h"
#include "formats/colmap_model.h"
#include "formats/image_masks.h"
#include "formats/ply.h"
#include "formats/scene_normalization.h"
#include "formats/sparse_tracks.h"
#include "formats/transforms_json.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr size_t kMinPointsForBounds = 8;
constexpr double kNearMargin = 0.8, kFarMargin = 1.2;

// The sfm stage's model is undistorted: its cameras are pinhole.
PinholeCamera Intrinsics(const ColmapCamera& camera) {
  std::array<double, 4> distortion;
  const PinholeCamera pinhole = PinholeFromColmap(camera, &distortion);
  if (distortion != std::array<double, 4>{}) {
    throw UserError(format("camera {} is a {} camera with distortion; the poses stage reads undistorted models",
                           camera.id, camera.model));
  }
  return pinhole;
}

// The views whose images are larger than `max_side` (0: none) or have a mask in `masks` (empty: none) name copies
// in `out`/images instead (PNG, the name kept): downsized, their intrinsics scaled to them, and with the mask as
// alpha. Views name their images from this stage's folder, whose staging copy `out` sits beside it.
void WriteChangedImages(const fs::path& out, int max_side, const fs::path& masks, std::vector<CameraView>* views) {
  std::vector<CameraView*> changed;
  int large = 0;
  for (CameraView& view : *views) {
    const bool downsize = max_side > 0 && std::max(view.camera.width, view.camera.height) > max_side;
    large += downsize;
    if (downsize || !masks.empty()) changed.push_back(&view);
  }
  if (changed.empty()) return;
  fs::create_directories(out / "images");
  Progress progress("poses: writing images", static_cast<int64_t>(changed.size()), "images");
  tbb::parallel_for(size_t{0}, changed.size(), [&](size_t i) {
    CameraView& view = *changed[i];
    const fs::path source = out / view.file_path;
    ReadImageResult read = ReadImage(source);
    if (!read.ok()) throw UserError(format("cannot use '{}': {}", source.string(), read.error));
    const std::string name = fs::path(view.file_path).filename().string();
    OIIO::ImageBuf image = masks.empty() ? std::move(read.image) : WithMask(read.image, source, masks / name);
    if (max_side > 0) image = DownsizeToFit(image, max_side);
    view.file_path = "images/" + (LowerExtension(name) == "png" ? name : name + ".png");
    const std::string error = WriteImage(image, out / view.file_path);
    if (!error.empty()) throw UserError(error);
    view.camera = ResizedCamera(view.camera, image.spec().width, image.spec().height);
    progress.Add();
  });
  if (large > 0) {
    LogInfo(format("poses: {} of {} images downsized to {} pixels on their longest side ({})", large, views->size(),
                   max_side, OptionKey(&PosesOptions::max_image_size)));
  }
  if (!masks.empty()) LogInfo(format("poses: the {} images take their masks as alpha", views->size()));
}

// Each view's points (indices in the model's order, as sparse_points.ply holds them) and each point's error.
SparseTracks TracksOf(const ColmapModel& model, const std::vector<const ColmapImage*>& images,
                      const std::vector<CameraView>& views) {
  SparseTracks tracks;
  std::map<uint64_t, uint32_t> index;
  for (const auto& [id, point] : model.points) {
    index.emplace(id, static_cast<uint32_t>(tracks.errors.size()));
    tracks.errors.push_back(static_cast<float>(point.error));
  }
  for (size_t i = 0; i < images.size(); ++i) {
    SparseTrackView view{views[i].file_path, {}};
    for (const uint64_t id : images[i]->point3d_ids) {
      const auto it = index.find(id);
      if (it != index.end()) view.points.push_back(it->second);
    }
    std::sort(view.points.begin(), view.points.end());
    view.points.erase(std::unique(view.points.begin(), view.points.end()), view.points.end());
    tracks.views.push_back(std::move(view));
  }
  return tracks;
}

}  // namespace

void PosesOptions::Check() const {
  CheckField(*this, holdout_every, holdout_every >= 0, "must be 0 (none) or positive");
  CheckField(*this, train_views, train_views >= 0, "must be 0 (all) or positive");
  CheckField(*this, max_image_size, max_image_size == 0 || max_image_size >= 16,
             format("must be 0 (as they are) or at least 16 pixels, not {}", max_image_size));
}

void PosesStage::Run(StageContext& context) const {
  const PosesOptions options = ReadOptions<PosesOptions>(context.config);
  const SfmResult sfm = Upstream<SfmResult>(context);
  const fs::path model_dir = sfm.undistorted_model();
  const ColmapModel model = ReadColmapModel(model_dir);
  if (model.images.empty()) throw UserError(format("the model in '{}' has no registered image", model_dir.string()));

  // Cameras in COLMAP's world, sorted by image name; near/far from the depths of the points each view sees.
  std::vector<const ColmapImage*> images;
  for (const auto& [id, image] : model.images) images.push_back(&image);
  std::sort(images.begin(), images.end(), [](const ColmapImage* a, const ColmapImage* b) { return a->name < b->name; });
  std::vector<CameraView> views;
  std::vector<Eigen::Vector3d> points;
  for (const auto& [id, point] : model.points) points.push_back(point.xyz);
  // transforms.json names the images relative to itself: from this stage's folder into the sfm stage's.
  const std::string images_from_poses =
      "../" + sfm.undistorted_images().lexically_relative(sfm.dir.parent_path()).generic_string() + "/";
  size_t without_bounds = 0;
  for (const ColmapImage* image : images) {
    CameraView view;
    view.file_path = images_from_poses + image->name;
    view.camera = Intrinsics(model.cameras.at(image->camera_id));
    view.camera.world_from_cam =
        WorldFromOpenGlCamera(image->cam_from_world_rotation, image->cam_from_world_translation);
    std::vector<double> depths;
    const Eigen::Matrix3d cv_from_world = image->cam_from_world_rotation.toRotationMatrix();
    for (const uint64_t id : image->point3d_ids) {
      const auto it = model.points.find(id);
      if (id == kNoPoint3D || it == model.points.end()) continue;
      const double z = (cv_from_world * it->second.xyz + image->cam_from_world_translation).z();
      if (z > 0 && std::isfinite(z)) depths.push_back(z);
    }
    if (depths.size() >= kMinPointsForBounds) {
      view.near = kNearMargin * Quantile(depths, 0.01);
      view.far = kFarMargin * Quantile(depths, 0.99);
    } else {
      ++without_bounds;  // the writer bounds it by the unit cube
    }
    views.push_back(view);
  }
  if (without_bounds > 0) LogWarning(format("poses: {} views see too few points for depth bounds", without_bounds));
  const bool masked = options.masks && fs::is_directory(sfm.undistorted_masks());
  WriteChangedImages(context.output_dir, options.max_image_size, masked ? sfm.undistorted_masks() : fs::path(), &views);
  const std::string heldout_rule = AssignHoldout(&views, options.holdout_every, true);
  KeepTrainingViews(&views, options.train_views);

  Normalization normalization;
  if (options.normalize) {
    std::vector<Eigen::Vector3d> centres, ups, axes;
    CameraFrames(views, &centres, &ups, &axes);
    normalization = NormalizeScene(centres, ups, axes, points);
    for (const std::string& warning : normalization.warnings) LogWarning("poses: " + warning);
  }
  TransformsFile transforms;
  transforms.views = NormalizedViews(views, normalization);
  transforms.meta.normalization = normalization;
  transforms.meta.heldout_rule = heldout_rule;
  const PosesResult out{context.output_dir};
  transforms.Write(out.transforms());

  std::vector<ColouredPoint> cloud;
  for (const auto& [id, point] : model.points) {
    cloud.push_back(
        {(normalization.normalized_from_world * point.xyz.homogeneous()).head<3>().cast<float>(), point.rgb});
  }
  WritePly(out.sparse_points(), cloud);
  TracksOf(model, images, transforms.views).Write(out.sparse_tracks());
  const size_t held_out =
      std::count_if(views.begin(), views.end(), [](const CameraView& v) { return v.split != ViewSplit::kTrain; });
  context.summary = {{"views", views.size()}, {"held_out", held_out}, {"points", cloud.size()}};
  LogInfo(format("poses: {} views ({} held out: {}), scene scale {:.4g} (centre from {}, up from {})", views.size(),
                 held_out, heldout_rule.empty() ? "none" : heldout_rule, normalization.scale, normalization.centre_from,
                 normalization.up_from));
}

}  // namespace p2n
