#include "stages/splat_viewer.h"

#include "pipeline/file_util.h"
#include "splat/compressed_ply.h"
#include "viewer/viewer_page.h"

namespace p2n {

size_t WriteSplatViewer(const std::filesystem::path& path, const std::string& title, const Gaussians<float>& gaussians,
                        const TrainingData& data, const OutputFrame& frame, const std::array<float, 3>& background,
                        double near) {
  ViewerScene scene;
  scene.title = title;
  scene.background = background;
  for (const auto& [views, split] : {std::pair{&data.train, "train"}, std::pair{&data.heldout, "heldout"}}) {
    for (const TrainView& view : *views) {
      const PinholeCamera& c = view.camera;
      scene.cameras.push_back({view.name, split, c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.world_from_cam});
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
