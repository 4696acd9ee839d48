#include "stages/fitting/splat_viewer.h"

#include "base/file_util.h"
#include "splat/compressed_ply.h"
#include "viewer/viewer_page.h"

namespace p2n {

size_t WriteSplatViewer(const std::filesystem::path& path, const std::string& title, const Gaussians<float>& gaussians,
                        const TrainingData& data, const OutputFrame& frame, const std::array<float, 3>& background,
                        double near) {
  SplatViewerScene scene;
  scene.title = title;
  scene.background = background;
  for (const auto& [views, split] : {std::pair{&data.train, "train"}, std::pair{&data.heldout, "heldout"}}) {
    for (const TrainView& view : *views) {
      const PinholeCamera& c = view.camera;
      SplatViewerCamera& camera = scene.cameras.emplace_back();
      camera.name = view.name;
      camera.split = split;
      camera.width = c.width, camera.height = c.height;
      camera.fx = c.fx, camera.fy = c.fy, camera.cx = c.cx, camera.cy = c.cy;
      Eigen::Map<Eigen::Matrix4d>(camera.world_from_cam.data()) = c.world_from_cam;  // column-major
    }
  }
  // The normalised frame puts what the cameras look at in the unit box about the origin.
  scene.centre = frame.Point(Eigen::Vector3f::Zero()).cast<double>();
  scene.radius = frame.Scale();
  scene.near = near;
  scene.far = 1000 * scene.radius;
  const std::string page = ViewerPage(scene, CompressedSplatPlyBytes(gaussians));
  WriteFileAtomic(path, page);
  return page.size();
}

}  // namespace p2n
