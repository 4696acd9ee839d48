#pragma once
// What the render stage draws views with: the trained field (ray marching) or the splats baked from it
// (rasterized), behind one call that takes a camera of the normalised frame and gives the image, the depth along
// the rays (normalised units) and the opacity.

#include <array>
#include <filesystem>
#include <functional>
#include <string>

#include "base/camera.h"
#include "base/enum_names.h"
#include "formats/dataset_import.h"
#include "nerf/nerf_model.h"
#include "nerf/renderer.h"
#include "stages/stage_reports.h"
#include "stages/stage_results.h"

namespace p2n {

struct ViewRenderer {
  RenderSource source = RenderSource::kField;
  std::array<float, 3> background{1, 1, 1};
  bool bounded = true;  // the scene lies in the unit box
  // Renders `camera` between `near` and `far` (the field's; splats ignore them); on_pixels_done(n) may report
  // progress or stop the work by throwing.
  std::function<RenderedView(const PinholeCamera& camera, double near, double far,
                             const std::function<void(size_t)>& on_pixels_done)>
      render;
};

// The field, rendered with `options` (its progress callback is replaced by each call's).
ViewRenderer FieldRenderer(const NerfModel& model, const RenderOptions& options);
// The splats of the splat stage's result `splat` and its `report`; UserError naming splats.ply when it cannot be
// read. `poses` is the poses stage's transforms.json (LoadTransformsJson), for the splats' frame.
ViewRenderer SplatRenderer(const SplatResult& splat, const SplatReport& report, const ImportedDataset& poses,
                           bool bounded);

}  // namespace p2n
