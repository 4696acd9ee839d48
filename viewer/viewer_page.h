#pragma once
// viewer.html: one self-contained page (no network) that shows a scene's splats live in the browser, starting
// from one of its cameras: the splats as a compressed PLY in base64, the cameras and the scene's extent as JSON,
// and the bundled script (three.js and Spark) that draws them.

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace p2n {

struct SplatViewerCamera {
  std::string name;
  std::string split;  // "train" or "heldout"
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::array<double, 16> world_from_cam{};  // column-major; OpenGL axes, in the splats' frame
};

struct SplatViewerScene {
  std::string title;
  std::array<float, 3> background{1, 1, 1};
  std::vector<SplatViewerCamera> cameras;            // the first training camera is where the page starts
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // what the orbit turns about
  double radius = 1;                                 // the scene's size: how fast the keys fly
  double near = 0.01, far = 100;
};

// The page. `splats` is a compressed splat PLY (splat/compressed_ply.h).
std::string ViewerPage(const SplatViewerScene& scene, const std::vector<char>& splats);

// A view of a textured mesh to put in a page's body: a canvas `width` x `height` (CSS pixels), the glTF binary
// `glb` in base64, and the bundled script (three.js) that draws it and lets the mouse turn round it.
std::string MeshViewHtml(const std::string& glb, int width, int height);

std::string Base64(const char* data, size_t size);

}  // namespace p2n
