#include "stages/ingest/import_stage.h"

#include <OpenImageIO/imagebufalgo.h>
#include <tbb/parallel_for.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/image_io.h"
#include "formats/dataset_import.h"
#include "formats/image_masks.h"
#include "formats/ply.h"
#include "formats/sparse_tracks.h"
#include "pipeline/hash.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"
#include "stages/ingest/plain_background.h"
#include "stages/sfm/poses_options.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

fs::path Input(const Workspace& workspace) {
  if (!workspace.input()) throw UserError("the workspace has no dataset; run `photo2nerf run DATASET -w WS`");
  return *workspace.input();
}

// The dataset read with its masks when poses.masks takes them from its MasksFolder.
ImportedDataset LoadWithMasks(const fs::path& input, const PosesOptions& options) {
  ImportedDataset dataset = LoadDataset(input);
  const fs::path masks = MasksFolder(input);
  if (!options.masks || masks.empty()) return dataset;
  std::vector<fs::path> photos;
  for (const ImportedView& view : dataset.views) {
    if (view.source.empty()) return dataset;  // pixels inside the dataset file (.npz): no photo to match
    photos.push_back(view.source);
  }
  const std::vector<fs::path> matched = MatchMasks(masks, photos);
  for (size_t i = 0; i < matched.size(); ++i) {
    dataset.views[i].mask = matched[i];
    dataset.files.push_back(matched[i]);
  }
  return dataset;
}

// Undistorts to the same pinhole intrinsics (OpenCV's k1, k2, p1, p2 model, as COLMAP's OPENCV).
OIIO::ImageBuf Undistort(const OIIO::ImageBuf& image, const PinholeCamera& camera, const std::array<double, 4>& d) {
  const OIIO::ImageSpec& spec = image.spec();
  const int depth = spec.format == OIIO::TypeDesc::UINT8    ? CV_8U
                    : spec.format == OIIO::TypeDesc::UINT16 ? CV_16U
                                                            : CV_32F;
  const cv::Mat source(spec.height, spec.width, CV_MAKETYPE(depth, spec.nchannels),
                       const_cast<void*>(image.localpixels()));
  OIIO::ImageBuf out(spec);
  cv::Mat target(spec.height, spec.width, CV_MAKETYPE(depth, spec.nchannels), out.localpixels());
  // Pixel centres: OpenCV puts pixel (0, 0)'s centre at (0, 0), we at (0.5, 0.5); shift the principal point.
  const cv::Matx33d k_opencv(camera.fx, 0, camera.cx - 0.5, 0, camera.fy, camera.cy - 0.5, 0, 0, 1);
  cv::Mat map_x, map_y;
  cv::initUndistortRectifyMap(k_opencv, cv::Vec4d(d[0], d[1], d[2], d[3]), cv::Mat(), k_opencv, target.size(), CV_32FC1,
                              map_x, map_y);
  cv::remap(source, target, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

struct ImageCounts {
  std::atomic<int> undistorted{0}, transparent{0}, downsized{0}, masked{0};
};

// What each opaque image shows along its border (BorderPixels), by view; KnownBackground reads them only when no
// image has alpha.
using Borders = std::vector<std::vector<Rgb>>;

// Writes the dataset's images into `images` as the poses stage's are: undistorted, downsized to `max_side` (0: any
// size), copied when nothing changed them; the views then name them and hold no distortion. Transparent images keep
// their alpha, so that training can put random colours behind them (a fixed colour lets the field paint fog of that
// colour over it at no cost).
void WriteImages(ImportedDataset& dataset, int max_side, const fs::path& images, ImageCounts* counts,
                 Borders* borders) {
  fs::create_directories(images);
  borders->assign(dataset.views.size(), {});
  Progress progress("import: images", static_cast<int64_t>(dataset.views.size()), "images");
  tbb::parallel_for(size_t{0}, dataset.views.size(), [&](size_t i) {
    ImportedView& view = dataset.views[i];
    const PinholeCamera& camera = view.view.camera;
    OIIO::ImageBuf image;
    if (view.source.empty()) {
      image = std::move(view.pixels);
    } else {
      ReadImageResult read = ReadImage(view.source);
      if (!read.ok()) throw UserError(format("cannot use '{}': {}", view.source.string(), read.error));
      image = std::move(read.image);
    }
    if (image.spec().width != camera.width || image.spec().height != camera.height) {
      throw UserError(format("'{}' is {}x{} but the dataset declares {}x{}", view.source.string(), image.spec().width,
                             image.spec().height, camera.width, camera.height));
    }
    bool changed = view.source.empty();
    if (!view.mask.empty()) {
      image = WithMask(image, view.source, view.mask);
      changed = true;
      ++counts->masked;
    }
    if (view.view.distortion != std::array<double, 4>{}) {
      image = Undistort(image, camera, view.view.distortion);
      view.view.distortion = {};
      changed = true;
      ++counts->undistorted;
    }
    if (image.spec().nchannels == 4 || image.spec().nchannels == 2) {
      ++counts->transparent;
    } else {
      (*borders)[i] = BorderPixels(image);
    }
    if (max_side > 0 && std::max(camera.width, camera.height) > max_side) {
      image = DownsizeToFit(image, max_side);
      view.view.camera = ResizedCamera(camera, image.spec().width, image.spec().height);
      changed = true;
      ++counts->downsized;
    }
    const std::string extension = LowerExtension(view.source);
    if (!changed && (extension == "png" || extension == "jpg" || extension == "jpeg")) {
      fs::copy_file(view.source, images / view.name, fs::copy_options::overwrite_existing);
    } else {
      if (fs::path(view.name).extension() != ".png") view.name = fs::path(view.name).replace_extension(".png").string();
      view.view.file_path = "images/" + view.name;
      const std::string error = WriteImage(image, images / view.name);
      if (!error.empty()) throw UserError(error);
    }
    progress.Add();
  });
}

// The colour transparent images are shown on (import.background; none for "keep"), or else the one the borders of
// all the images show (a dataset rendered on a plain background, as the NeRF course's .npz); none for photos.
std::optional<Rgb> KnownBackground(const ImportOptions& options, const ImageCounts& counts, const Borders& borders) {
  if (counts.transparent > 0) {
    if (options.background == ImportBackground::kKeep) return std::nullopt;
    return options.background == ImportBackground::kWhite ? Rgb{1, 1, 1} : Rgb{0, 0, 0};
  }
  std::vector<Rgb> pixels;
  for (const std::vector<Rgb>& border : borders) pixels.insert(pixels.end(), border.begin(), border.end());
  return SharedColour(std::move(pixels));
}

// transforms.json of the dataset's cameras (normalised, with a held-out split unless the dataset has one) and
// sparse_points.ply when it has points, as the poses stage writes them.
Normalization WriteCameras(const ImportedDataset& dataset, const fs::path& input, const PosesOptions& poses,
                           const std::optional<Rgb>& background, const PosesResult& out) {
  TransformsFile transforms;
  for (const ImportedView& view : dataset.views) transforms.views.push_back(view.view);
  std::vector<CameraView>& views = transforms.views;
  const bool has_split =
      std::any_of(views.begin(), views.end(), [](const CameraView& v) { return v.split != ViewSplit::kTrain; });
  // LLFF data keeps the NeRF paper's protocol (every 8th from the first), whatever its size.
  if (!has_split)
    transforms.meta.heldout_rule = AssignHoldout(&views, poses.holdout_every, dataset.kind != DatasetKind::kLlff);
  KeepTrainingViews(&views, poses.train_views);
  Normalization& normalization = transforms.meta.normalization;
  if (poses.normalize) {
    std::vector<Eigen::Vector3d> centres, ups, axes;
    CameraFrames(views, &centres, &ups, &axes);
    // LLFF data keeps the frame its cameras give (the points it may ship came later to it, for their depths).
    const bool llff = dataset.kind == DatasetKind::kLlff;
    normalization = NormalizeScene(centres, ups, axes, llff ? std::vector<Eigen::Vector3d>{} : dataset.points);
    for (const std::string& warning : normalization.warnings) LogWarning("import: " + warning);
  }
  views = NormalizedViews(views, normalization);
  transforms.meta.dataset_kind = dataset.kind;
  transforms.meta.dataset_path = input.string();
  transforms.meta.background = background;
  transforms.Write(out.transforms());
  if (!dataset.points.empty()) {
    std::vector<ColouredPoint> cloud;
    for (size_t i = 0; i < dataset.points.size(); ++i) {
      cloud.push_back({(normalization.normalized_from_world * dataset.points[i].homogeneous()).head<3>().cast<float>(),
                       dataset.colours[i]});
    }
    WritePly(out.sparse_points(), cloud);
  }
  if (!dataset.view_points.empty()) {
    SparseTracks tracks{dataset.point_errors, {}};
    for (size_t i = 0; i < views.size(); ++i) tracks.views.push_back({views[i].file_path, dataset.view_points[i]});
    tracks.Write(out.sparse_tracks());
  }
  return normalization;
}

}  // namespace

std::map<std::string, std::string> ImportStage::ExternalInputs(const Workspace& workspace, const Config& config) const {
  const fs::path input = Input(workspace);
  std::vector<fs::path> files;
  try {
    files = LoadWithMasks(input, ReadOptions<PosesOptions>(config)).files;
  } catch (const UserError&) {
    return {{"dataset " + input.string(), "unreadable"}};  // Run() says why
  }
  const std::vector<std::string> digests = Sha1OfFiles(files);
  std::map<std::string, std::string> inputs;
  for (size_t i = 0; i < files.size(); ++i)
    inputs["file " + fs::relative(files[i], input.has_extension() ? input.parent_path() : input).string()] = digests[i];
  return inputs;
}

void ImportStage::Run(StageContext& context) const {
  const PosesOptions poses = ReadOptions<PosesOptions>(context.config);
  const ImportOptions options = ReadOptions<ImportOptions>(context.config);
  const fs::path input = Input(context.workspace);
  ImportedDataset dataset = LoadWithMasks(input, poses);
  for (const std::string& warning : dataset.warnings) LogWarning("import: " + warning);
  LogInfo(format("import: {} dataset, {} views", EnumName(dataset.kind), dataset.views.size()));
  ImageCounts counts;
  Borders borders;
  const PosesResult out{context.output_dir};
  WriteImages(dataset, poses.max_image_size, out.images(), &counts, &borders);
  const std::optional<Rgb> background = KnownBackground(options, counts, borders);
  const Normalization normalization = WriteCameras(dataset, input, poses, background, out);
  context.summary = {{"views", dataset.views.size()}, {"dataset", EnumName(dataset.kind)}};
  LogInfo(
      format("import: {} views ({} masked, {} undistorted, {} with alpha, {} downsized to {} px), scene scale {:.4g}",
             dataset.views.size(), counts.masked.load(), counts.undistorted.load(), counts.transparent.load(),
             counts.downsized.load(), poses.max_image_size, normalization.scale));
  if (background) {
    LogInfo(format("import: the images are shown on a plain background ({:.3f}, {:.3f}, {:.3f})", (*background)[0],
                   (*background)[1], (*background)[2]));
  }
}

}  // namespace p2n
