#include "stages/view_renders.h"

#include <algorithm>
#include <cmath>

#include "pipeline/cancel.h"
#include "pipeline/hash.h"
#include "pipeline/progress.h"

namespace p2n {
namespace {

// Names everything the renders depend on: the model's bytes, the width, each view's camera and bounds.
std::string RendersKey(const std::filesystem::path& model_file, const std::vector<TrainView>& views, int width) {
  Hasher hasher;
  hasher.Field("view renders, median depth").Field(Sha1OfFile(model_file)).Field(width);
  for (const TrainView& view : views) {
    const PinholeCamera& c = view.camera;
    const double values[] = {double(c.width), double(c.height), c.fx, c.fy, c.cx, c.cy, view.near, view.far};
    hasher.Bytes(values, sizeof(values)).Bytes(c.world_from_cam.data(), 16 * sizeof(double));
  }
  return hasher.HexDigest();
}

// The pixels of `cameras` scaled to `width`.
size_t PixelsAt(const std::vector<PinholeCamera>& cameras, int width) {
  size_t pixels = 0;
  for (const PinholeCamera& camera : cameras) {
    const PinholeCamera scaled = ScaledCamera(camera, width);
    pixels += size_t(scaled.width) * scaled.height;
  }
  return pixels;
}

}  // namespace

int SmallViewsWidth(const std::vector<PinholeCamera>& cameras, int width, size_t max_pixels) {
  const size_t pixels = PixelsAt(cameras, width);
  if (pixels <= max_pixels) return width;
  return std::max(1, static_cast<int>(width * std::sqrt(double(max_pixels) / double(pixels))));
}

std::shared_ptr<const ViewRenders> RenderViewsSmall(const StageContext& context,
                                                    const std::filesystem::path& model_file, const NerfModel& model,
                                                    const std::vector<TrainView>& views, int width,
                                                    const std::string& label) {
  std::vector<PinholeCamera> cameras;
  for (const TrainView& view : views) cameras.push_back(view.camera);
  width = SmallViewsWidth(cameras, width);
  std::string key;
  if (context.memo != nullptr) {
    key = RendersKey(model_file, views, width);
    if (auto found = context.memo->Find<ViewRenders>(key)) return found;
  }
  auto result = std::make_shared<ViewRenders>();
  for (const PinholeCamera& camera : cameras) result->cameras.push_back(ScaledCamera(camera, width));
  Progress progress(label, static_cast<int64_t>(PixelsAt(cameras, width)), "pixels");
  RenderOptions render;
  render.median_depth = true;
  render.on_rays_done = [&](size_t n) {
    progress.Add(static_cast<int64_t>(n));
    ThrowIfCancelled();  // Ctrl-C stops within a tile
  };
  for (size_t i = 0; i < views.size(); ++i) {
    result->renders.push_back(RenderView(model, result->cameras[i], views[i].near, views[i].far, render));
  }
  std::shared_ptr<const ViewRenders> renders = std::move(result);
  if (context.memo != nullptr) context.memo->Keep(key, renders);
  return renders;
}

}  // namespace p2n
