#include "formats/transforms_json.h"

#include "formats/camera_geometry.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/image_io.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr double kUnitCubeRadius = 1.7320508075688772;  // half the diagonal of [-1, 1]^3
constexpr double kRotationTolerance = 1e-3;
const char* const kDistortionKeys[] = {"k1", "k2", "p1", "p2"};

nlohmann::json MatrixJson(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
}

// A 4x4 or 3x4 matrix (the fourth row then 0 0 0 1).
Eigen::Matrix4d Matrix(const nlohmann::json& rows, const fs::path& file, const std::string& field) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (!rows.is_array() || rows.size() < 3) ThrowBadField(file, field, "is not a 4x4 (or 3x4) matrix");
  for (size_t r = 0; r < rows.size() && r < 4; ++r) {
    if (!rows[r].is_array() || rows[r].size() != 4) ThrowBadField(file, field, "is not a 4x4 (or 3x4) matrix");
    for (int c = 0; c < 4; ++c) {
      if (!rows[r][c].is_number()) ThrowBadField(file, field, "holds something that is not a number");
      m(r, c) = rows[r][c].get<double>();
    }
  }
  return m;
}

// An image's width or height: a whole number of pixels, written as an integer or (instant-ngp) as 1080.0.
int Pixels(const nlohmann::json& value, const fs::path& file, const std::string& field) {
  const double pixels = value.is_number() ? value.get<double>() : 0.0;
  if (!(pixels >= 1 && pixels <= kMaxImageSide && pixels == std::floor(pixels)))
    ThrowBadField(file, field,
                  format("must be a whole number of pixels, 1 to {}, not {}", kMaxImageSide, value.dump()));
  return static_cast<int>(pixels);
}

nlohmann::json Intrinsics(const PinholeCamera& camera) {
  return {{"camera_model", "PINHOLE"},
          {"fl_x", camera.fx},
          {"fl_y", camera.fy},
          {"cx", camera.cx},
          {"cy", camera.cy},
          {"w", camera.width},
          {"h", camera.height},
          {"camera_angle_x", 2 * std::atan(camera.width / (2 * camera.fx))},
          {"camera_angle_y", 2 * std::atan(camera.height / (2 * camera.fy))}};
}

bool SameIntrinsics(const PinholeCamera& a, const PinholeCamera& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy;
}

nlohmann::json FrameJson(const CameraView& view, bool shared_intrinsics) {
  nlohmann::json frame = {{"file_path", view.file_path},
                          {"transform_matrix", MatrixJson(view.camera.world_from_cam)},
                          {"split", EnumName(view.split)},
                          {"near", view.near},
                          {"far", view.far}};
  if (!shared_intrinsics) frame.update(Intrinsics(view.camera));
  for (int k = 0; k < 4; ++k) {
    if (view.distortion[k] != 0) frame[kDistortionKeys[k]] = view.distortion[k];
  }
  return frame;
}

nlohmann::json MetaJson(const TransformsMeta& meta) {
  const Normalization& n = meta.normalization;
  nlohmann::json json = {{"aabb_scale", 1},
                         {"applied_transform", MatrixJson(n.normalized_from_world.topRows<3>())},
                         {"applied_scale", n.scale},
                         {"normalization", {{"centre_from", n.centre_from}, {"up_from", n.up_from}}}};
  if (meta.dataset_kind) json["dataset"] = {{"kind", EnumName(*meta.dataset_kind)}, {"path", meta.dataset_path}};
  if (meta.background) json["background"] = *meta.background;
  if (!meta.heldout_rule.empty()) json["heldout_rule"] = meta.heldout_rule;
  if (!meta.frame.empty()) json.update({{"frame", meta.frame}, {"cameras_refined", meta.cameras_refined}});
  return json;
}

std::pair<int, int> ImageSize(const fs::path& image) {
  std::string error;
  const ImageFileHeader header = ReadImageHeader(image, &error);
  if (!error.empty()) throw UserError(format("cannot read the image '{}': {}", image.string(), error));
  return {header.width, header.height};
}

// The view of frames[i], or none when its image is missing; intrinsics from the frame, else the top level.
std::optional<CameraView> ReadFrame(const nlohmann::json& json, size_t i, const fs::path& file, const fs::path& root,
                                    ViewSplit split) {
  const nlohmann::json& frame = json["frames"][i];
  const std::string field = format("frames[{}]", i);
  if (!frame.is_object()) ThrowBadField(file, field, "is not an object");
  const auto value = [&](const char* key) -> const nlohmann::json* {
    if (frame.contains(key)) return &frame[key];
    if (json.contains(key)) return &json[key];
    return nullptr;
  };
  if (!frame.contains("file_path") || !frame["file_path"].is_string())
    ThrowBadField(file, field + ".file_path", "is missing");
  CameraView view;
  view.file_path = frame["file_path"].get<std::string>();
  if (fs::path(view.file_path).is_absolute() || !IsInside(root, TransformsFile::ImagePath(file, view))) {
    ThrowBadField(file, field + ".file_path",
                  format("points outside the dataset folder ('{}'); refused", view.file_path));
  }
  fs::path image = TransformsFile::ImagePath(file, view);
  if (!image.has_extension() && fs::exists(image.string() + ".png")) {  // Blender leaves it out
    view.file_path += ".png";
    image += ".png";
  }
  if (!fs::exists(image)) return std::nullopt;
  view.split = split;
  if (frame.contains("split")) {
    const std::optional<ViewSplit> named =
        frame["split"].is_string() ? EnumFromName<ViewSplit>(frame["split"].get<std::string>()) : std::nullopt;
    if (!named) ThrowBadField(file, field + ".split", "must be one of " + EnumNamesText<ViewSplit>());
    view.split = *named;
  }
  view.near = frame.value("near", -1.0);
  view.far = frame.value("far", -1.0);
  PinholeCamera& camera = view.camera;
  camera.world_from_cam = Matrix(frame.value("transform_matrix", nlohmann::json()), file, field + ".transform_matrix");
  std::tie(camera.width, camera.height) =
      value("w") && value("h")
          ? std::pair<int, int>{Pixels(*value("w"), file, field + ".w"), Pixels(*value("h"), file, field + ".h")}
          : ImageSize(image);
  if (value("fl_x")) {
    camera.fx = value("fl_x")->get<double>();
    camera.fy = value("fl_y") ? value("fl_y")->get<double>() : camera.fx;
  } else if (value("camera_angle_x")) {
    camera.fx = camera.fy = 0.5 * camera.width / std::tan(0.5 * value("camera_angle_x")->get<double>());
  } else {
    ThrowBadField(file, field, "has no focal length (fl_x or camera_angle_x)");
  }
  camera.cx = value("cx") ? value("cx")->get<double>() : 0.5 * camera.width;
  camera.cy = value("cy") ? value("cy")->get<double>() : 0.5 * camera.height;
  for (int k = 0; k < 4; ++k)
    view.distortion[k] = value(kDistortionKeys[k]) ? value(kDistortionKeys[k])->get<double>() : 0.0;
  CheckCamera(camera, file, field);
  return view;
}

TransformsMeta ReadMeta(const nlohmann::json& json, const fs::path& file) {
  TransformsMeta meta;
  Normalization& n = meta.normalization;
  if (json.contains("applied_transform"))
    n.normalized_from_world = Matrix(json["applied_transform"], file, "applied_transform");
  n.scale = json.value("applied_scale", 1.0);
  if (json.contains("normalization")) {
    n.centre_from = json["normalization"].value("centre_from", "");
    n.up_from = json["normalization"].value("up_from", "");
  }
  if (json.contains("dataset")) {
    const std::string kind = json["dataset"].value("kind", "");
    meta.dataset_kind = EnumFromName<DatasetKind>(kind);
    if (!meta.dataset_kind)
      ThrowBadField(file, "dataset.kind", format("is '{}', not {}", kind, EnumNamesText<DatasetKind>()));
    meta.dataset_path = json["dataset"].value("path", "");
  }
  if (json.contains("background") && !json["background"].is_null()) {
    const nlohmann::json& rgb = json["background"];
    if (!rgb.is_array() || rgb.size() != 3)
      ThrowBadField(file, "background", "must be three numbers (red, green, blue)");
    meta.background = rgb.get<std::array<float, 3>>();
  }
  if (json.contains("heldout_rule")) {
    if (!json["heldout_rule"].is_string()) ThrowBadField(file, "heldout_rule", "must be a string");
    meta.heldout_rule = json["heldout_rule"].get<std::string>();
  }
  meta.frame = json.value("frame", "");
  meta.cameras_refined = json.value("cameras_refined", false);
  return meta;
}

TransformsFile ReadUnchecked(const fs::path& file, const fs::path& root, ViewSplit split) {
  const nlohmann::json json = ReadJsonFile(file);
  if (!json.is_object()) ThrowBadField(file, "the file", "is not a JSON object");
  if (!json.contains("frames") || !json["frames"].is_array()) ThrowBadField(file, "frames", "is missing");
  TransformsFile out;
  out.meta = ReadMeta(json, file);
  size_t missing = 0;
  for (size_t i = 0; i < json["frames"].size(); ++i) {
    std::optional<CameraView> view = ReadFrame(json, i, file, root, split);
    if (view) {
      out.views.push_back(std::move(*view));
    } else {
      ++missing;
    }
  }
  if (missing > 0) {
    out.warnings.push_back(
        format("{}: {} frames name images that are not there; they are left out", file.string(), missing));
  }
  return out;
}

}  // namespace

void CheckCamera(const PinholeCamera& camera, const fs::path& file, const std::string& field) {
  if (!camera.world_from_cam.allFinite()) ThrowBadField(file, field, "has a camera pose that is not finite");
  const Eigen::Matrix3d r = camera.world_from_cam.topLeftCorner<3, 3>();
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > kRotationTolerance || r.determinant() < 0) {
    ThrowBadField(file, field, "has a camera rotation that is not orthonormal (a scaled or mirrored matrix?)");
  }
  if (!(camera.fx > 0) || !(camera.fy > 0) || !std::isfinite(camera.fx) || !std::isfinite(camera.fy) ||
      !std::isfinite(camera.cx) || !std::isfinite(camera.cy)) {
    ThrowBadField(file, field, "has a focal length that is not a positive number");
  }
  if (camera.width <= 0 || camera.height <= 0) ThrowBadField(file, field, "has no image size");
}

void TransformsFile::Write(const fs::path& file) const {
  const bool shared = std::all_of(views.begin(), views.end(), [&](const CameraView& view) {
    return SameIntrinsics(view.camera, views.front().camera);
  });
  nlohmann::json json = shared && !views.empty() ? Intrinsics(views.front().camera) : nlohmann::json::object();
  nlohmann::json frames = nlohmann::json::array();
  for (const CameraView& view : views) frames.push_back(FrameJson(view, shared));
  json["frames"] = frames;
  json.update(MetaJson(meta));
  WriteJsonAtomic(file, json);
}

TransformsFile TransformsFile::Read(const fs::path& file, const fs::path& root, ViewSplit split) {
  try {
    return ReadUnchecked(file, root, split);
  } catch (const nlohmann::json::exception& e) {
    throw UserError(format("'{}' has a value of the wrong type ({}); fix the file", file.string(), e.what()));
  }
}

fs::path TransformsFile::ImagePath(const fs::path& file, const CameraView& view) {
  return (file.parent_path() / view.file_path).lexically_normal();
}

std::vector<CameraView> NormalizedViews(const std::vector<CameraView>& views, const Normalization& normalization) {
  std::vector<CameraView> out = views;
  for (CameraView& view : out) {
    Eigen::Matrix4d& pose = view.camera.world_from_cam;
    pose = normalization.normalized_from_world * pose;
    pose.topLeftCorner<3, 3>() /= normalization.scale;  // a rotation again: the scale applies to positions only
    // Unknown bounds: the unit cube as seen from the camera.
    const double distance = pose.topRightCorner<3, 1>().norm();
    view.near = view.near > 0 ? view.near * normalization.scale : std::max(0.01, distance - kUnitCubeRadius);
    view.far = view.far > 0 ? view.far * normalization.scale : distance + kUnitCubeRadius;
  }
  return out;
}

void KeepTrainingViews(std::vector<CameraView>* views, int count) {
  std::vector<CameraView*> train;
  for (CameraView& view : *views) {
    if (view.split == ViewSplit::kTrain) train.push_back(&view);
  }
  const size_t n = train.size();
  if (count <= 0 || size_t(count) >= n) return;
  std::vector<bool> keep(n, false);
  if (count == 1) keep[n / 2] = true;
  for (int i = 0; count > 1 && i < count; ++i) keep[std::lround(double(i) * double(n - 1) / (count - 1))] = true;
  for (size_t i = 0; i < n; ++i) {
    if (!keep[i]) train[i]->split = ViewSplit::kUnused;
  }
}

std::string AssignHoldout(std::vector<CameraView>* views, int every, bool inside_span) {
  std::vector<CameraView*> open;  // the views without a split of their own
  for (CameraView& view : *views) {
    if (view.split != ViewSplit::kVal && view.split != ViewSplit::kTest) open.push_back(&view);
  }
  for (CameraView* view : open) view->split = ViewSplit::kTrain;
  if (every <= 0 || open.empty()) return "";
  if (!inside_span || open.size() >= kFewViews) {
    for (size_t i = 0; i < open.size(); i += every) open[i]->split = ViewSplit::kVal;
    return format("every {}th view from the first", every);
  }
  // As many as every Nth would hold out, each the view nearest an even spread over the sequence (away from its
  // ends) whose camera lies inside the span of the views left to train on.
  const size_t n = open.size(), count = (n + every - 1) / every;
  const auto centre = [&](size_t i) -> Eigen::Vector3d {
    return open[i]->camera.world_from_cam.topRightCorner<3, 1>();
  };
  const auto inside = [&](size_t candidate) {
    std::vector<Eigen::Vector3d> training;
    for (size_t i = 0; i < n; ++i) {
      if (i != candidate && open[i]->split == ViewSplit::kTrain) training.push_back(centre(i));
    }
    return !OutsideSpan(training, centre(candidate));
  };
  for (size_t k = 0; k < count; ++k) {
    const long ideal = static_cast<long>((2 * k + 1) * n / (2 * count));
    long chosen = -1;
    for (long offset = 0; offset < static_cast<long>(n) && chosen < 0; ++offset) {
      for (const long i : {ideal - offset, ideal + offset}) {
        if (i < 0 || i >= static_cast<long>(n) || open[i]->split != ViewSplit::kTrain || !inside(i)) continue;
        chosen = i;
        break;
      }
    }
    if (chosen < 0) chosen = open[ideal]->split == ViewSplit::kTrain ? ideal : -1;  // none inside: the even spread
    if (chosen >= 0) open[chosen]->split = ViewSplit::kVal;
  }
  return format(
      "{} of {} views, spread over the capture inside the span of the others (fewer than {} photos: "
      "the first and last would test extrapolation)",
      count, n, kFewViews);
}

void CameraFrames(const std::vector<CameraView>& views, std::vector<Eigen::Vector3d>* centres,
                  std::vector<Eigen::Vector3d>* ups, std::vector<Eigen::Vector3d>* axes) {
  for (const CameraView& view : views) {
    centres->push_back(view.camera.world_from_cam.topRightCorner<3, 1>());
    ups->push_back(view.camera.world_from_cam.block<3, 1>(0, 1));    // OpenGL +y
    axes->push_back(-view.camera.world_from_cam.block<3, 1>(0, 2));  // OpenGL cameras look down -z
  }
}

}  // namespace p2n
