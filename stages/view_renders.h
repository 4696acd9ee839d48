#pragma once
// The training views rendered small by the trained field, with their median depths: the splat stage places its
// first splats from them and the export stage makes its point cloud from them. Whichever of the two runs first in a
// run renders them; the other finds them in the run's memo when it asks for the same views of the same model at the
// same width, and renders them itself when run alone. Either way the renders are the same. A pixel gives at most
// one point, so no more than kMaxSmallViewPixels are rendered in all.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "nerf/renderer.h"
#include "nerf/trainer.h"
#include "pipeline/stage.h"

namespace p2n {

inline constexpr size_t kMaxSmallViewPixels = 2'000'000;

// The width the views are rendered at: `width`, or narrower where `cameras` would give more than `max_pixels`
// pixels in all.
int SmallViewsWidth(const std::vector<PinholeCamera>& cameras, int width, size_t max_pixels = kMaxSmallViewPixels);

struct ViewRenders {
  std::vector<PinholeCamera> cameras;  // the views' cameras scaled to the width
  std::vector<RenderedView> renders;   // of each camera, depths the median ones
};

// `views` (cameras and near/far in the field's frame; their pixels are not read) rendered `width` pixels wide
// (SmallViewsWidth) by `model`, read from `model_file`. `label` names the work on the progress line.
std::shared_ptr<const ViewRenders> RenderViewsSmall(const StageContext& context,
                                                    const std::filesystem::path& model_file, const NerfModel& model,
                                                    const std::vector<TrainView>& views, int width,
                                                    const std::string& label);

}  // namespace p2n
