#include "formats/dataset_import.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/image_io.h"
#include "formats/colmap_model.h"
#include "formats/npy.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

// One transforms.json (instant-ngp, nerfstudio, or one Blender split) into views.
TransformsMeta AddTransforms(const fs::path& root, const fs::path& file, ViewSplit split, ImportedDataset* out) {
  TransformsFile transforms = TransformsFile::Read(file, root, split);
  out->files.push_back(file);
  for (CameraView& camera : transforms.views) {
    ImportedView view;
    view.source = TransformsFile::ImagePath(file, camera);
    view.view = std::move(camera);
    out->files.push_back(view.source);
    out->views.push_back(std::move(view));
  }
  out->warnings.insert(out->warnings.end(), transforms.warnings.begin(), transforms.warnings.end());
  return transforms.meta;
}

// The model's points, their errors and each view's points (`view_of`: image id to view index).
void AddPoints(const std::map<uint64_t, ColmapPoint3D>& points, const std::map<uint32_t, size_t>& view_of,
               ImportedDataset* out) {
  out->view_points.assign(out->views.size(), {});
  for (const auto& [id, point] : points) {
    const uint32_t index = static_cast<uint32_t>(out->points.size());
    out->points.push_back(point.xyz);
    out->colours.push_back(point.rgb);
    out->point_errors.push_back(static_cast<float>(point.error));
    for (const auto& [image, unused] : point.track) {
      const auto it = view_of.find(image);
      if (it != view_of.end()) out->view_points[it->second].push_back(index);
    }
  }
  for (std::vector<uint32_t>& list : out->view_points) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
}

// The share of the tracks' observations that project in front of their view and inside its image.
double ShareInFrame(const ImportedDataset& dataset) {
  size_t inside = 0, total = 0;
  for (size_t v = 0; v < dataset.views.size(); ++v) {
    const PinholeCamera& camera = dataset.views[v].view.camera;
    for (const uint32_t p : dataset.view_points[v]) {
      double depth;
      const Eigen::Vector2d pixel = Project(camera, dataset.points[p], &depth);
      inside +=
          depth > 0 && pixel.x() >= 0 && pixel.y() >= 0 && pixel.x() <= camera.width && pixel.y() <= camera.height;
      ++total;
    }
  }
  return total == 0 ? 0 : double(inside) / total;
}

// LLFF's sparse/0/points3D.bin when the dataset ships it (fern does, without images.bin): COLMAP numbered the
// images in the order LLFF sorts them, so the k-th image id is the k-th view. That is a convention, so it is
// checked: the tracks are kept only when nearly all their observations fall inside their views.
void AddLlffPoints(const fs::path& root, ImportedDataset* out) {
  const fs::path file = root / "sparse" / "0" / "points3D.bin";
  if (!fs::exists(file)) return;
  const std::map<uint64_t, ColmapPoint3D> points = ReadColmapPointsBinary(file);
  out->files.push_back(file);
  std::set<uint32_t> ids;
  for (const auto& [id, point] : points) {
    if (!point.xyz.allFinite() || !std::isfinite(point.error))
      ThrowBadField(file, format("point {}", id), "is not finite");
    for (const auto& [image, unused] : point.track) ids.insert(image);
  }
  std::map<uint32_t, size_t> view_of;
  if (ids.size() == out->views.size()) {
    for (const uint32_t id : ids) view_of.emplace(id, view_of.size());
  }
  AddPoints(points, view_of, out);
  constexpr double kMinShareInFrame = 0.95;
  if (view_of.empty() || ShareInFrame(*out) < kMinShareInFrame) {
    out->warnings.push_back(
        format("'{}': its tracks do not fit the views in order; its points are kept without them", file.string()));
    out->view_points.clear();
  }
}

void LoadLlff(const fs::path& root, ImportedDataset* out) {
  const fs::path file = root / "poses_bounds.npy";
  const NpyArray poses = ReadNpy(file);
  out->files.push_back(file);
  if (poses.shape.size() != 2 || poses.shape[1] != 17) ThrowBadField(file, "the array", "must have shape (N, 17)");
  // The image folder: images/ at full size, else the largest downsampled one (images_4, images_8, ...).
  fs::path images;
  for (const char* name : {"images", "images_2", "images_4", "images_8", "images_16"}) {
    if (fs::is_directory(root / name)) {
      images = root / name;
      break;
    }
  }
  if (images.empty()) ThrowBadField(root, "the LLFF dataset", "has no images/ or images_N/ folder");
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(images)) {
    const std::string extension = LowerExtension(entry.path());
    if (extension == "png" || extension == "jpg" || extension == "jpeg") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (files.size() != poses.shape[0]) {
    ThrowBadField(file, "the array",
                  format("has {} poses but {} holds {} images", poses.shape[0], images.string(), files.size()));
  }
  for (size_t i = 0; i < files.size(); ++i) {
    const double* row = poses.values.data() + 17 * i;
    // Row-major 3x5: [R | t | (H, W, focal)], rotation columns in LLFF order (down, right, backwards).
    Eigen::Matrix<double, 3, 5> m;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 5; ++c) m(r, c) = row[5 * r + c];
    }
    std::string error;
    const ImageFileHeader header = ReadImageHeader(files[i], &error);
    if (!error.empty()) ThrowBadField(files[i], "the image", "cannot be read: " + error);
    const int width = header.width, height = header.height;
    const double factor = m(1, 4) / width;  // full-resolution width over this folder's
    ImportedView view;
    view.source = files[i];
    PinholeCamera& camera = view.view.camera;
    camera.world_from_cam.block<3, 1>(0, 0) = m.col(1);   // right
    camera.world_from_cam.block<3, 1>(0, 1) = -m.col(0);  // up = -down
    camera.world_from_cam.block<3, 1>(0, 2) = m.col(2);   // backwards
    camera.world_from_cam.block<3, 1>(0, 3) = m.col(3);
    camera.width = width;
    camera.height = height;
    camera.fx = camera.fy = m(2, 4) / factor;
    camera.cx = 0.5 * width;
    camera.cy = 0.5 * height;
    view.view.near = row[15];
    view.view.far = row[16];
    CheckCamera(camera, file, format("row {}", i));
    out->files.push_back(files[i]);
    out->views.push_back(std::move(view));
  }
  AddLlffPoints(root, out);
}

void LoadColmapProject(const fs::path& root, ImportedDataset* out) {
  const fs::path sparse = fs::exists(root / "sparse" / "0") ? root / "sparse" / "0" : root / "sparse";
  const ColmapModel model = ReadColmapModel(sparse);
  for (const char* name : {"cameras.bin", "images.bin", "points3D.bin", "cameras.txt", "images.txt", "points3D.txt"}) {
    if (fs::exists(sparse / name)) out->files.push_back(sparse / name);
  }
  for (const auto& [id, image] : model.images) {
    const ColmapCamera& colmap = model.cameras.at(image.camera_id);
    ImportedView view;
    view.source = (root / "images" / image.name).lexically_normal();
    if (!IsInside(root, view.source))
      ThrowBadField(sparse, format("image {}", id),
                    format("names 'images/{}', outside the dataset folder; refused", image.name));
    if (!fs::exists(view.source))
      ThrowBadField(sparse, format("image {}", id), format("names '{}', which is not there", view.source.string()));
    PinholeCamera& camera = view.view.camera;
    camera = PinholeFromColmap(colmap, &view.view.distortion);
    camera.world_from_cam = WorldFromOpenGlCamera(image.cam_from_world_rotation, image.cam_from_world_translation);
    CheckCamera(camera, sparse, format("image {}", id));
    out->files.push_back(view.source);
    out->views.push_back(std::move(view));
  }
  std::map<uint32_t, size_t> view_of;
  for (const auto& [id, image] : model.images) view_of.emplace(id, view_of.size());
  AddPoints(model.points, view_of, out);
}

void LoadNpz(const fs::path& file, ImportedDataset* out) {
  const auto arrays = ReadNpz(file);
  out->files.push_back(file);
  const auto get = [&](const std::string& name) -> const NpyArray& {
    const auto it = arrays.find(name);
    if (it == arrays.end()) ThrowBadField(file, name, "is missing");
    return it->second;
  };
  const NpyArray& focal = get("focal");
  if (focal.size() != 1 || !(focal.values[0] > 0)) ThrowBadField(file, "focal", "must be one positive number");
  for (const ViewSplit split : {ViewSplit::kTrain, ViewSplit::kVal}) {
    const std::string name = EnumName(split);
    const NpyArray& images = get("images_" + name);
    const NpyArray& poses = get("c2ws_" + name);
    if (images.shape.size() != 4 || (images.shape[3] != 3 && images.shape[3] != 4)) {
      ThrowBadField(file, "images_" + name, "must have shape (N, H, W, 3 or 4)");
    }
    if (poses.shape != std::vector<size_t>{images.shape[0], 4, 4}) {
      ThrowBadField(file, "c2ws_" + name, "must have shape (N, 4, 4) with one pose per image");
    }
    const int height = static_cast<int>(images.shape[1]), width = static_cast<int>(images.shape[2]);
    const int channels = static_cast<int>(images.shape[3]);
    const bool floats = *std::max_element(images.values.begin(), images.values.end()) <= 1.0;
    for (size_t i = 0; i < images.shape[0]; ++i) {
      ImportedView view;
      view.name = format("{}_{:03d}.png", name, i);
      view.view.split = split;
      PinholeCamera& camera = view.view.camera;
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) camera.world_from_cam(r, c) = poses.values[i * 16 + r * 4 + c];
      }
      camera.width = width;
      camera.height = height;
      camera.fx = camera.fy = focal.values[0];
      camera.cx = 0.5 * width;
      camera.cy = 0.5 * height;
      CheckCamera(camera, file, format("c2ws_{}[{}]", name, i));
      view.pixels.reset(OIIO::ImageSpec(width, height, channels, OIIO::TypeDesc::UINT8));
      uint8_t* pixels = static_cast<uint8_t*>(view.pixels.localpixels());
      const double* values = images.values.data() + i * height * width * channels;
      for (size_t k = 0; k < static_cast<size_t>(height) * width * channels; ++k) {
        pixels[k] = static_cast<uint8_t>(std::lround(std::clamp(floats ? values[k] * 255 : values[k], 0.0, 255.0)));
      }
      out->views.push_back(std::move(view));
    }
  }
}

// The .npz file a dataset is: `input` itself, or the (last) one in the folder `input`.
fs::path NpzFile(const fs::path& input) {
  fs::path file = input;
  if (fs::is_directory(input)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(input)) {
      if (LowerExtension(entry.path()) == "npz") file = entry.path();
    }
  }
  return file;
}

}  // namespace

std::vector<PinholeCamera> ImportedDataset::Cameras() const {
  std::vector<PinholeCamera> cameras;
  for (const ImportedView& view : views) cameras.push_back(view.view.camera);
  return cameras;
}

std::optional<DatasetKind> DetectDataset(const fs::path& input) {
  if (fs::is_regular_file(input) && LowerExtension(input) == "npz") return DatasetKind::kNpz;
  if (!fs::is_directory(input)) return std::nullopt;
  if (fs::exists(input / "transforms.json")) return DatasetKind::kTransformsJson;
  if (fs::exists(input / "transforms_train.json")) return DatasetKind::kBlender;
  if (fs::exists(input / "poses_bounds.npy")) return DatasetKind::kLlff;
  if (fs::is_directory(input / "images") && fs::is_directory(input / "sparse")) return DatasetKind::kColmap;
  for (const fs::directory_entry& entry : fs::directory_iterator(input)) {
    if (LowerExtension(entry.path()) == "npz") return DatasetKind::kNpz;
  }
  return std::nullopt;
}

ImportedDataset LoadTransformsJson(const fs::path& file, const fs::path& root) {
  ImportedDataset dataset;
  dataset.meta = AddTransforms(root, file, ViewSplit::kTrain, &dataset);
  if (dataset.views.empty()) throw UserError(format("'{}' has no view whose image exists", file.string()));
  return dataset;
}

ImportedDataset LoadDataset(const fs::path& input) {
  const std::optional<DatasetKind> kind = DetectDataset(input);
  if (!kind) throw UserError(format("'{}' is not a dataset with cameras", input.string()));
  ImportedDataset dataset;
  dataset.kind = *kind;
  switch (*kind) {
    case DatasetKind::kTransformsJson:
      AddTransforms(input, input / "transforms.json", ViewSplit::kTrain, &dataset);
      break;
    case DatasetKind::kBlender:
      for (const ViewSplit split : {ViewSplit::kTrain, ViewSplit::kVal, ViewSplit::kTest}) {
        const fs::path file = input / (std::string("transforms_") + EnumName(split) + ".json");
        if (fs::exists(file)) AddTransforms(input, file, split, &dataset);
      }
      break;
    case DatasetKind::kLlff:
      LoadLlff(input, &dataset);
      break;
    case DatasetKind::kColmap:
      LoadColmapProject(input, &dataset);
      break;
    case DatasetKind::kNpz:
      LoadNpz(NpzFile(input), &dataset);
      break;
  }
  if (dataset.views.empty()) throw UserError(format("the dataset '{}' has no usable view", input.string()));
  // Output names: the source file names, made unique by their folder where two share one (Blender splits).
  std::map<std::string, int> seen;
  for (ImportedView& view : dataset.views) {
    if (!view.name.empty()) continue;
    const std::string plain = view.source.filename().string();
    view.name = seen[plain]++ == 0 ? plain : view.source.parent_path().filename().string() + "_" + plain;
  }
  std::map<std::string, int> names;
  for (ImportedView& view : dataset.views) {
    if (names[view.name]++ > 0) view.name = EnumName(view.view.split) + ("_" + view.name);
    view.view.file_path = "images/" + view.name;
  }
  return dataset;
}

}  // namespace p2n
