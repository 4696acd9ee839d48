#include "stages/transforms_json.h"

#include <cmath>

#include "pipeline/file_util.h"

namespace p2n {
namespace {

constexpr double kUnitCubeRadius = 1.7320508075688772;  // half the diagonal of [-1, 1]^3

nlohmann::json MatrixJson(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(row);
  }
  return rows;
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

}  // namespace

void AssignHoldout(std::vector<CameraView>* views, int every) {
  for (size_t i = 0; i < views->size(); ++i) {
    CameraView& view = (*views)[i];
    if (view.split == "val" || view.split == "test") continue;
    view.split = every > 0 && i % every == 0 ? "val" : "train";
  }
}

void CameraFrames(const std::vector<CameraView>& views, std::vector<Eigen::Vector3d>* centres,
                  std::vector<Eigen::Vector3d>* ups, std::vector<Eigen::Vector3d>* axes) {
  for (const CameraView& view : views) {
    centres->push_back(view.camera.world_from_cam.topRightCorner<3, 1>());
    ups->push_back(view.camera.world_from_cam.block<3, 1>(0, 1));    // OpenGL +y
    axes->push_back(-view.camera.world_from_cam.block<3, 1>(0, 2));  // OpenGL cameras look down -z
  }
}

void WriteTransformsJson(const std::filesystem::path& path, const std::vector<CameraView>& views,
                         const Normalization& normalization, const nlohmann::json& extra) {
  const Eigen::Matrix4d& normalized_from_world = normalization.normalized_from_world;
  const double scale = normalization.scale;
  bool shared = true;
  for (const CameraView& view : views) {
    const PinholeCamera& a = view.camera;
    const PinholeCamera& b = views.front().camera;
    shared = shared && a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx &&
             a.cy == b.cy;
  }
  nlohmann::json transforms = shared ? Intrinsics(views.front().camera) : nlohmann::json::object();
  nlohmann::json frames = nlohmann::json::array();
  for (const CameraView& view : views) {
    Eigen::Matrix4d normalized_from_cam = normalized_from_world * view.camera.world_from_cam;
    normalized_from_cam.topLeftCorner<3, 3>() /= scale;  // a rotation again: the scale applies to positions only
    // Unknown bounds: the unit cube as seen from the camera.
    const double distance = normalized_from_cam.topRightCorner<3, 1>().norm();
    const double near = view.near > 0 ? view.near * scale : std::max(0.01, distance - kUnitCubeRadius);
    const double far = view.far > 0 ? view.far * scale : distance + kUnitCubeRadius;
    nlohmann::json frame = {{"file_path", view.file_path},
                            {"transform_matrix", MatrixJson(normalized_from_cam)},
                            {"split", view.split},
                            {"near", near},
                            {"far", far}};
    if (!shared) frame.update(Intrinsics(view.camera));
    frames.push_back(frame);
  }
  transforms["frames"] = frames;
  transforms["aabb_scale"] = 1;
  transforms["applied_transform"] = MatrixJson(normalized_from_world.topRows<3>());
  transforms["applied_scale"] = scale;
  transforms["normalization"] = {{"centre_from", normalization.centre_from}, {"up_from", normalization.up_from}};
  transforms.update(extra);
  WriteJsonAtomic(path, transforms);
}

}  // namespace p2n
