#include "stages/training_data.h"

#include <OpenImageIO/imagebufalgo.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/image_io.h"
#include "formats/ply.h"
#include "formats/sparse_tracks.h"
#include "nerf/forward_space.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"
#include "stages/stage_results.h"

namespace p2n {
namespace fs = std::filesystem;

namespace {

// The view's camera and name, without its pixels.
TrainView ViewWithoutPixels(const ImportedView& imported) {
  TrainView view;
  view.camera = imported.view.camera;
  view.near = imported.view.near;
  view.far = imported.view.far;
  view.name = imported.source.filename().string();
  return view;
}

// UserError when the image's size is not its camera's.
void CheckImageSize(const ImportedView& imported, int width, int height) {
  const PinholeCamera& camera = imported.view.camera;
  if (width != camera.width || height != camera.height) {
    throw UserError(format("'{}' is {}x{} but transforms.json says {}x{}; rerun the poses stage",
                           imported.source.string(), width, height, camera.width, camera.height));
  }
}

// The channels LoadTrainView makes of an image's: grey expanded to RGB, beyond four cut to RGBA.
int LoadedChannels(int channels) { return channels <= 2 ? channels + 2 : std::min(channels, 4); }

}  // namespace

TrainView TrainViewHeader(const ImportedView& imported) {
  TrainView view = ViewWithoutPixels(imported);
  std::string error;
  const ImageFileHeader header = ReadImageHeader(imported.source, &error);
  if (!error.empty()) throw UserError(format("cannot read '{}': {}", imported.source.string(), error));
  const bool turned = header.orientation >= 5;  // a quarter turn
  CheckImageSize(imported, turned ? header.height : header.width, turned ? header.width : header.height);
  view.channels = LoadedChannels(header.channels);
  return view;
}

TrainView LoadTrainView(const ImportedView& imported) {
  TrainView view = ViewWithoutPixels(imported);
  const ReadImageResult read = ReadImage(imported.source);
  if (!read.ok()) throw UserError(format("cannot read '{}': {}", imported.source.string(), read.error));
  OIIO::ImageBuf image = read.image;
  const int channels = image.spec().nchannels;
  if (channels == 1 || channels == 2) {
    const int order[] = {0, 0, 0, 1};
    image = OIIO::ImageBufAlgo::channels(image, channels + 2, OIIO::cspan<int>(order, channels + 2));
  } else if (channels > 4) {
    image = OIIO::ImageBufAlgo::channels(image, 4, {});
  }
  const OIIO::ImageSpec& spec = image.spec();
  CheckImageSize(imported, spec.width, spec.height);
  view.channels = spec.nchannels;
  view.pixels.resize(size_t(spec.width) * spec.height * spec.nchannels);
  if (!image.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::UINT8, view.pixels.data())) {
    throw UserError(format("cannot convert '{}': {}", imported.source.string(), image.geterror()));
  }
  return view;
}

ViewSplit HeldoutSplit(const ImportedDataset& dataset) {
  const bool has_test = std::any_of(dataset.views.begin(), dataset.views.end(),
                                    [](const ImportedView& v) { return v.view.split == ViewSplit::kTest; });
  return has_test ? ViewSplit::kTest : ViewSplit::kVal;
}

bool ForwardFacingCapture(const ImportedDataset& dataset) { return FacesForward(dataset.Cameras()); }

namespace {

// The points of `tracks` that `view` sees, where they appear in it (in front, inside the image).
std::vector<DepthPoint> ViewDepthPoints(const ImportedView& view, const SparseTracks& tracks,
                                        const std::vector<ColouredPoint>& points) {
  std::vector<DepthPoint> out;
  const PinholeCamera& camera = view.view.camera;
  const Eigen::Vector3d centre = camera.world_from_cam.topRightCorner<3, 1>();
  for (const uint32_t index : tracks.PointsOf(view.view.file_path)) {
    const Eigen::Vector3d point = points[index].position.cast<double>();
    double depth;
    const Eigen::Vector2d pixel = Project(camera, point, &depth);
    if (!(depth > 0) || pixel.x() < 0 || pixel.y() < 0 || pixel.x() >= camera.width || pixel.y() >= camera.height)
      continue;
    out.push_back({static_cast<float>(pixel.x()), static_cast<float>(pixel.y()),
                   static_cast<float>((point - centre).norm()), tracks.errors[index]});
  }
  return out;
}

void AddDepthPoints(const ImportedDataset& poses, const std::vector<const ImportedView*>& train, TrainingData* data) {
  const PosesResult files{poses.files.front().parent_path()};
  if (!fs::exists(files.sparse_tracks())) {
    LogInfo(format("train: no depth loss: the poses have no sparse points with tracks ('{}')",
                   files.sparse_tracks().string()));
    return;
  }
  const SparseTracks tracks = SparseTracks::Read(files.sparse_tracks());
  const std::vector<ColouredPoint> points = ReadPly(files.sparse_points());
  if (points.size() != tracks.errors.size()) {
    throw UserError(format("'{}' has {} points but '{}' tracks {}; rerun the poses stage",
                           files.sparse_points().string(), points.size(), files.sparse_tracks().string(),
                           tracks.errors.size()));
  }
  size_t count = 0;
  for (size_t i = 0; i < train.size(); ++i) {
    data->train[i].depth_points = ViewDepthPoints(*train[i], tracks, points);
    count += data->train[i].depth_points.size();
  }
  LogInfo(format("train: {} depth points in {} training views", count, train.size()));
}

}  // namespace

namespace {

std::vector<const ImportedView*> SplitViews(const ImportedDataset& poses, ViewSplit split) {
  std::vector<const ImportedView*> views;
  for (const ImportedView& view : poses.views) {
    if (view.view.split == split) views.push_back(&view);
  }
  return views;
}

}  // namespace

std::vector<const ImportedView*> TrainingViews(const ImportedDataset& poses) {
  return SplitViews(poses, ViewSplit::kTrain);
}

std::vector<const ImportedView*> HeldoutViews(const ImportedDataset& poses) {
  return SplitViews(poses, HeldoutSplit(poses));
}

namespace {

// The data's background and its `count` training views, none loaded; UserError when there are none.
TrainingData Unloaded(const ImportedDataset& poses, size_t count) {
  if (count == 0) {  // files.front(): the transforms.json
    throw UserError(format("'{}' has no training view (split \"train\")", poses.files.front().string()));
  }
  TrainingData data;
  data.background = poses.meta.Background();
  data.background_known = poses.meta.background.has_value();
  data.train.resize(count);
  return data;
}

void LoadHeaders(const std::vector<const ImportedView*>& views, std::vector<TrainView>* loaded) {
  loaded->resize(views.size());
  tbb::parallel_for(size_t{0}, views.size(), [&](size_t i) { (*loaded)[i] = TrainViewHeader(*views[i]); });
}

}  // namespace

TrainingData LoadTrainingData(const ImportedDataset& poses, bool depth_points, double photo_bytes) {
  const std::vector<const ImportedView*> train = TrainingViews(poses);
  const std::vector<const ImportedView*> heldout = HeldoutViews(poses);
  TrainingData data = Unloaded(poses, train.size());
  data.heldout.resize(heldout.size());
  size_t loaded = train.size(), heldout_loaded = heldout.size();
  if (std::isfinite(photo_bytes)) {
    LoadHeaders(train, &data.train);
    LoadHeaders(heldout, &data.heldout);
    heldout_loaded = 0;
    double bytes = 0;
    for (const TrainView& view : data.train) bytes += view.PixelBytes();
    if (bytes > photo_bytes) loaded = 0;
  }
  std::optional<Progress> progress;
  if (loaded + heldout_loaded > 0) progress.emplace("loading images", int64_t(loaded + heldout_loaded), "images");
  tbb::parallel_for(size_t{0}, loaded + heldout_loaded, [&](size_t i) {
    if (i < loaded) {
      data.train[i] = LoadTrainView(*train[i]);
    } else {
      data.heldout[i - loaded] = LoadTrainView(*heldout[i - loaded]);
    }
    progress->Add();
  });
  if (depth_points) AddDepthPoints(poses, train, &data);
  return data;
}

TrainingData LoadTrainingCameras(const ImportedDataset& poses, bool depth_points) {
  const std::vector<const ImportedView*> train = TrainingViews(poses);
  TrainingData data = Unloaded(poses, train.size());
  LoadHeaders(train, &data.train);
  if (depth_points) AddDepthPoints(poses, train, &data);
  return data;
}

std::vector<std::string> ViewNames(const std::vector<TrainView>& views) {
  std::vector<std::string> names;
  for (const TrainView& view : views) names.push_back(view.name);
  return names;
}

void CheckSameViews(const std::vector<std::string>& names, const std::vector<TrainView>& views, const std::string& who,
                    const std::filesystem::path& transforms) {
  if (names.empty()) return;
  for (size_t v = 0; v < std::max(names.size(), views.size()); ++v) {
    if (v < names.size() && v < views.size() && views[v].name == names[v]) continue;
    const std::string& name = v < names.size() ? names[v] : views[v].name;
    throw UserError(
        format("{}: the training photos of {} here are not those the blocks were cut from ('{}', training view {}, "
               "differs): check that every photo of the poses stage can be read on this machine (a file system "
               "every node shares), then run the stage again",
               who, transforms.string(), name, v + 1));
  }
}

}  // namespace p2n
