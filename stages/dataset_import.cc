#include "stages/dataset_import.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>

#include "pipeline/errors.h"
#include "pipeline/file_util.h"
#include "pipeline/format.h"
#include "stages/colmap_model.h"
#include "stages/npy.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr double kRotationTolerance = 1e-3;
const char* kBlenderSplits[] = {"train", "val", "test"};

[[noreturn]] void Bad(const fs::path& file, const std::string& field, const std::string& problem) {
  throw UserError(format("'{}': {} {}", file.string(), field, problem));
}

void CheckCamera(const PinholeCamera& camera, const fs::path& file, const std::string& field) {
  if (!camera.world_from_cam.allFinite()) Bad(file, field, "has a camera pose that is not finite");
  const Eigen::Matrix3d r = camera.world_from_cam.topLeftCorner<3, 3>();
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > kRotationTolerance || r.determinant() < 0) {
    Bad(file, field, "has a camera rotation that is not orthonormal (a scaled or mirrored matrix?)");
  }
  if (!(camera.fx > 0) || !(camera.fy > 0) || !std::isfinite(camera.fx) || !std::isfinite(camera.fy) ||
      !std::isfinite(camera.cx) || !std::isfinite(camera.cy)) {
    Bad(file, field, "has a focal length that is not a positive number");
  }
  if (camera.width <= 0 || camera.height <= 0) Bad(file, field, "has no image size");
}

// A path named in `file` relative to `base`, which must resolve inside `root`; refused when it leads outside.
fs::path InsideDataset(const fs::path& root, const fs::path& relative_to, const fs::path& file,
                       const std::string& relative, const std::string& field) {
  const fs::path resolved = (relative_to / relative).lexically_normal();
  const fs::path base = root.lexically_normal();
  const auto [end, ignored] = std::mismatch(base.begin(), base.end(), resolved.begin(), resolved.end());
  if (end != base.end() || fs::path(relative).is_absolute()) {
    Bad(file, field, format("points outside the dataset folder ('{}'); refused", relative));
  }
  return resolved;
}

Eigen::Matrix4d Matrix(const nlohmann::json& rows, const fs::path& file, const std::string& field) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (!rows.is_array() || rows.size() < 3) Bad(file, field, "is not a 4x4 (or 3x4) matrix");
  for (size_t r = 0; r < rows.size() && r < 4; ++r) {
    if (!rows[r].is_array() || rows[r].size() != 4) Bad(file, field, "is not a 4x4 (or 3x4) matrix");
    for (int c = 0; c < 4; ++c) {
      if (!rows[r][c].is_number()) Bad(file, field, "holds something that is not a number");
      m(r, c) = rows[r][c].get<double>();
    }
  }
  return m;
}

std::pair<int, int> ImageSize(const fs::path& image) {
  auto input = OIIO::ImageInput::open(image.string());
  if (!input) throw UserError(format("cannot read the image '{}': {}", image.string(), OIIO::geterror()));
  return {input->spec().width, input->spec().height};
}

// One transforms.json (instant-ngp, nerfstudio, or one Blender split) into views.
void ReadTransforms(const fs::path& root, const fs::path& file, const std::string& split, ImportedDataset* out) {
  const nlohmann::json transforms = ReadJsonFile(file);
  out->files.push_back(file);
  if (!transforms.contains("frames") || !transforms["frames"].is_array()) Bad(file, "frames", "is missing");
  size_t missing = 0;
  for (size_t i = 0; i < transforms["frames"].size(); ++i) {
    const nlohmann::json& frame = transforms["frames"][i];
    const std::string field = format("frames[{}]", i);
    const auto value = [&](const char* key) -> const nlohmann::json* {
      if (frame.contains(key)) return &frame[key];
      if (transforms.contains(key)) return &transforms[key];
      return nullptr;
    };
    if (!frame.contains("file_path") || !frame["file_path"].is_string()) Bad(file, field + ".file_path", "is missing");
    fs::path image =
        InsideDataset(root, file.parent_path(), file, frame["file_path"].get<std::string>(), field + ".file_path");
    if (!image.has_extension() && fs::exists(image.string() + ".png")) image += ".png";  // Blender leaves it out
    if (!fs::exists(image)) {
      ++missing;  // instant-ngp's fox lists 17 frames whose images are not shipped
      continue;
    }
    ImportedView view;
    view.source = image;
    view.view.split = frame.contains("split") ? frame["split"].get<std::string>() : split;  // ours has one
    view.view.near = frame.value("near", -1.0);
    view.view.far = frame.value("far", -1.0);
    PinholeCamera& camera = view.view.camera;
    camera.world_from_cam =
        Matrix(frame.value("transform_matrix", nlohmann::json()), file, field + ".transform_matrix");
    const auto [width, height] = value("w") && value("h")
                                     ? std::pair<int, int>{value("w")->get<int>(), value("h")->get<int>()}
                                     : ImageSize(image);
    camera.width = width;
    camera.height = height;
    if (value("fl_x")) {
      camera.fx = value("fl_x")->get<double>();
      camera.fy = value("fl_y") ? value("fl_y")->get<double>() : camera.fx;
    } else if (value("camera_angle_x")) {
      camera.fx = camera.fy = 0.5 * width / std::tan(0.5 * value("camera_angle_x")->get<double>());
    } else {
      Bad(file, field, "has no focal length (fl_x or camera_angle_x)");
    }
    camera.cx = value("cx") ? value("cx")->get<double>() : 0.5 * width;
    camera.cy = value("cy") ? value("cy")->get<double>() : 0.5 * height;
    const char* distortion_keys[] = {"k1", "k2", "p1", "p2"};
    for (int k = 0; k < 4; ++k)
      view.distortion[k] = value(distortion_keys[k]) ? value(distortion_keys[k])->get<double>() : 0.0;
    CheckCamera(camera, file, field);
    out->files.push_back(image);
    out->views.push_back(std::move(view));
  }
  if (missing > 0) {
    out->warnings.push_back(
        format("{}: {} frames name images that are not there; they are left out", file.string(), missing));
  }
}

// ReadTransforms, with a JSON value of the wrong type reported as a user error naming the file.
void ReadTransformsChecked(const fs::path& root, const fs::path& file, const std::string& split, ImportedDataset* out) {
  try {
    ReadTransforms(root, file, split, out);
  } catch (const nlohmann::json::exception& e) {
    throw UserError(format("'{}' has a value of the wrong type ({}); fix the file", file.string(), e.what()));
  }
}

void LoadLlff(const fs::path& root, ImportedDataset* out) {
  const fs::path file = root / "poses_bounds.npy";
  const NpyArray poses = ReadNpy(file);
  out->files.push_back(file);
  if (poses.shape.size() != 2 || poses.shape[1] != 17) Bad(file, "the array", "must have shape (N, 17)");
  // The image folder: images/ at full size, else the largest downsampled one (images_4, images_8, ...).
  fs::path images;
  for (const char* name : {"images", "images_2", "images_4", "images_8", "images_16"}) {
    if (fs::is_directory(root / name)) {
      images = root / name;
      break;
    }
  }
  if (images.empty()) Bad(root, "the LLFF dataset", "has no images/ or images_N/ folder");
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(images)) {
    const std::string extension = LowerExtension(entry.path());
    if (extension == "png" || extension == "jpg" || extension == "jpeg") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (files.size() != poses.shape[0]) {
    Bad(file, "the array",
        format("has {} poses but {} holds {} images", poses.shape[0], images.string(), files.size()));
  }
  for (size_t i = 0; i < files.size(); ++i) {
    const double* row = poses.values.data() + 17 * i;
    // Row-major 3x5: [R | t | (H, W, focal)], rotation columns in LLFF order (down, right, backwards).
    Eigen::Matrix<double, 3, 5> m;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 5; ++c) m(r, c) = row[5 * r + c];
    }
    const auto [width, height] = ImageSize(files[i]);
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
    view.source = InsideDataset(root, root, sparse / "images", "images/" + image.name, format("image {}", id));
    if (!fs::exists(view.source))
      Bad(sparse, format("image {}", id), format("names '{}', which is not there", view.source.string()));
    PinholeCamera& camera = view.view.camera;
    camera = PinholeFromColmap(colmap, &view.distortion);
    camera.world_from_cam = WorldFromOpenGlCamera(image.cam_from_world_rotation, image.cam_from_world_translation);
    CheckCamera(camera, sparse, format("image {}", id));
    out->files.push_back(view.source);
    out->views.push_back(std::move(view));
  }
  for (const auto& [id, point] : model.points) {
    out->points.push_back(point.xyz);
    out->colours.push_back(point.rgb);
  }
}

void LoadNpz(const fs::path& file, ImportedDataset* out) {
  const auto arrays = ReadNpz(file);
  out->files.push_back(file);
  const auto get = [&](const std::string& name) -> const NpyArray& {
    const auto it = arrays.find(name);
    if (it == arrays.end()) Bad(file, name, "is missing");
    return it->second;
  };
  const NpyArray& focal = get("focal");
  if (focal.size() != 1 || !(focal.values[0] > 0)) Bad(file, "focal", "must be one positive number");
  for (const char* split : {"train", "val"}) {
    const NpyArray& images = get(std::string("images_") + split);
    const NpyArray& poses = get(std::string("c2ws_") + split);
    if (images.shape.size() != 4 || (images.shape[3] != 3 && images.shape[3] != 4)) {
      Bad(file, std::string("images_") + split, "must have shape (N, H, W, 3 or 4)");
    }
    if (poses.shape != std::vector<size_t>{images.shape[0], 4, 4}) {
      Bad(file, std::string("c2ws_") + split, "must have shape (N, 4, 4) with one pose per image");
    }
    const int height = static_cast<int>(images.shape[1]), width = static_cast<int>(images.shape[2]);
    const int channels = static_cast<int>(images.shape[3]);
    const bool floats = *std::max_element(images.values.begin(), images.values.end()) <= 1.0;
    for (size_t i = 0; i < images.shape[0]; ++i) {
      ImportedView view;
      view.name = format("{}_{:03d}.png", split, i);
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
      CheckCamera(camera, file, format("c2ws_{}[{}]", split, i));
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

}  // namespace

std::string DatasetKind(const fs::path& input) {
  if (fs::is_regular_file(input) && LowerExtension(input) == "npz") return "npz";
  if (!fs::is_directory(input)) return "";
  if (fs::exists(input / "transforms.json")) return "transforms.json";
  if (fs::exists(input / "transforms_train.json")) return "blender";
  if (fs::exists(input / "poses_bounds.npy")) return "llff";
  if (fs::is_directory(input / "images") && fs::is_directory(input / "sparse")) return "colmap";
  for (const fs::directory_entry& entry : fs::directory_iterator(input)) {
    if (LowerExtension(entry.path()) == "npz") return "npz";
  }
  return "";
}

ImportedDataset LoadTransformsJson(const fs::path& file, const fs::path& root) {
  ImportedDataset dataset;
  dataset.kind = "transforms.json";
  ReadTransformsChecked(root, file, "train", &dataset);
  if (dataset.views.empty()) throw UserError(format("'{}' has no view whose image exists", file.string()));
  return dataset;
}

ImportedDataset LoadDataset(const fs::path& input) {
  ImportedDataset dataset;
  dataset.kind = DatasetKind(input);
  if (dataset.kind == "transforms.json") {
    ReadTransformsChecked(input, input / "transforms.json", "train", &dataset);
  } else if (dataset.kind == "blender") {
    for (const char* split : kBlenderSplits) {
      const fs::path file = input / (std::string("transforms_") + split + ".json");
      if (fs::exists(file)) ReadTransformsChecked(input, file, split, &dataset);
    }
  } else if (dataset.kind == "llff") {
    LoadLlff(input, &dataset);
  } else if (dataset.kind == "colmap") {
    LoadColmapProject(input, &dataset);
  } else if (dataset.kind == "npz") {
    fs::path file = input;
    if (fs::is_directory(input)) {
      for (const fs::directory_entry& entry : fs::directory_iterator(input)) {
        if (LowerExtension(entry.path()) == "npz") file = entry.path();
      }
    }
    LoadNpz(file, &dataset);
  } else {
    throw UserError(format("'{}' is not a dataset with cameras", input.string()));
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
    if (names[view.name]++ > 0) view.name = view.view.split + "_" + view.name;
    view.view.file_path = "images/" + view.name;
  }
  return dataset;
}

}  // namespace p2n
