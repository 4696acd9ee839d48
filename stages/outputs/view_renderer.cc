#include "stages/outputs/view_renderer.h"

#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "formats/output_frame.h"
#include "splat/rasterizer.h"
#include "splat/splat_ply.h"
#include "stages/stage_reports.h"

namespace p2n {
namespace fs = std::filesystem;

ViewRenderer FieldRenderer(const NerfModel& model, const RenderOptions& options) {
  ViewRenderer renderer;
  renderer.source = RenderSource::kField;
  renderer.background = model.background;
  renderer.bounded = model.space == SceneSpace::kBounded;
  renderer.render = [&model, options](const PinholeCamera& camera, double near, double far,
                                      const std::function<void(size_t)>& on_pixels_done) {
    RenderOptions with_progress = options;
    with_progress.on_rays_done = on_pixels_done;
    return RenderView(model, camera, near, far, with_progress);
  };
  return renderer;
}

namespace {

// The splats' image of a camera given in the normalised frame, as RenderView gives the field's.
RenderedView RenderSplatView(const Gaussians<float>& splats, const OutputFrame& frame, const RasterOptions& options,
                             const PinholeCamera& camera) {
  const auto start = std::chrono::steady_clock::now();
  PinholeCamera moved = camera;
  moved.world_from_cam = frame.Pose(camera.world_from_cam);
  Rasterizer<float> rasterizer;
  rasterizer.Forward(splats, moved, options);
  RenderedView view;
  const int w = camera.width, h = camera.height;
  view.rgb = {w, h, 3, rasterizer.rgb()};
  view.opacity = {w, h, 1, std::vector<float>(size_t(w) * h)};
  view.depth = {w, h, 1, std::vector<float>(size_t(w) * h)};
  const double scale = frame.Scale();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const float opacity = 1 - rasterizer.transmittance()[i];
      view.opacity.pixels[i] = opacity;
      if (opacity <= 1e-6f) continue;
      // Depth along the view axis in the splats' frame -> distance along the pixel's ray, normalised units.
      const double u = (x + 0.5 - camera.cx) / camera.fx, v = (y + 0.5 - camera.cy) / camera.fy;
      view.depth.pixels[i] =
          static_cast<float>(rasterizer.weighted_depth()[i] / opacity / scale * std::sqrt(1 + u * u + v * v));
    }
  }
  view.stats.rays = size_t(w) * h;
  view.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return view;
}

}  // namespace

ViewRenderer SplatRenderer(const SplatResult& splat, const SplatReport& report, const ImportedDataset& poses,
                           bool bounded) {
  const fs::path file = splat.splats();
  std::shared_ptr<const Gaussians<float>> splats;
  try {
    splats = std::make_shared<const Gaussians<float>>(ReadSplatPly(file));
  } catch (const std::runtime_error& error) {
    throw UserError(format("{}; rerun the splat stage (photo2nerf splat -w WORKSPACE --force)", error.what()));
  }
  const OutputFrame frame = MakeOutputFrame(report.frame, poses);
  RasterOptions options;
  options.projection.near = report.near;
  ViewRenderer renderer;
  renderer.source = RenderSource::kSplats;
  renderer.bounded = bounded;
  renderer.background = report.background;
  for (int c = 0; c < 3; ++c) options.background[c] = report.background[c];
  renderer.render = [splats, frame, options](const PinholeCamera& camera, double, double,
                                             const std::function<void(size_t)>& on_pixels_done) {
    RenderedView view = RenderSplatView(*splats, frame, options, camera);
    if (on_pixels_done) on_pixels_done(view.stats.rays);
    return view;
  };
  return renderer;
}

}  // namespace p2n
