#include "stages/training_data.h"

#include <OpenImageIO/imagebufalgo.h>
#include <tbb/parallel_for.h>

#include <algorithm>

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

TrainView LoadTrainView(const ImportedView& imported) {
  TrainView view;
  view.camera = imported.view.camera;
  view.near = imported.view.near;
  view.far = imported.view.far;
  view.name = imported.source.filename().string();
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
  if (spec.width != view.camera.width || spec.height != view.camera.height) {
    throw UserError(format("'{}' is {}x{} but transforms.json says {}x{}; rerun the poses stage",
                           imported.source.string(), spec.width, spec.height, view.camera.width, view.camera.height));
  }
  view.channels = spec.nchannels;
  view.pixels.resize(size_t(spec.width) * spec.height * spec.nchannels);
  if (!image.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::UINT8, view.pixels.data())) {
    throw UserError(format("cannot convert '{}': {}", imported.source.string(), image.geterror()));
  }
  return view;
}

std::string HeldoutSplit(const ImportedDataset& dataset) {
  const bool has_test = std::any_of(dataset.views.begin(), dataset.views.end(),
                                    [](const ImportedView& v) { return v.view.split == "test"; });
  return has_test ? "test" : "val";
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

TrainingData LoadTrainingData(const ImportedDataset& poses, bool depth_points) {
  TrainingData data;
  data.background = poses.meta.Background();
  data.background_known = poses.meta.background.has_value();
  const std::string heldout_split = HeldoutSplit(poses);
  std::vector<const ImportedView*> train, heldout;
  for (const ImportedView& view : poses.views) {
    if (view.view.split == "train") train.push_back(&view);
    if (view.view.split == heldout_split) heldout.push_back(&view);
  }
  if (train.empty()) {  // files.front(): the transforms.json
    throw UserError(format("'{}' has no training view (split \"train\")", poses.files.front().string()));
  }
  data.train.resize(train.size());
  data.heldout.resize(heldout.size());
  Progress progress("train: loading images", static_cast<int64_t>(train.size() + heldout.size()), "images");
  tbb::parallel_for(size_t{0}, train.size() + heldout.size(), [&](size_t i) {
    if (i < train.size()) {
      data.train[i] = LoadTrainView(*train[i]);
    } else {
      data.heldout[i - train.size()] = LoadTrainView(*heldout[i - train.size()]);
    }
    progress.Add();
  });
  if (depth_points) AddDepthPoints(poses, train, &data);
  return data;
}

}  // namespace p2n
