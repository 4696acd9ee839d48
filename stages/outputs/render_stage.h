#pragma once
// The render stage: renders a trained model (the field, or the splats baked from it when they are as good:
// render.source) without its training data. The held-out views are compared with their photos (PSNR and SSIM per view
// and on average, eval.json, with error heat maps); a camera path (an orbit, a spiral in front of the capture, or
// cameras from a file) becomes frames, depth and opacity images and an MP4 video. Rendering marches through the model's
// occupancy grid with early termination, in tiles.

#include <filesystem>
#include <string>
#include <vector>

#include "base/camera.h"
#include "pipeline/options.h"
#include "stages/outputs/render_options.h"
#include "stages/outputs/view_renderer.h"
#include "stages/stage_results.h"

namespace p2n {

// The cameras of a path file: frames[].transform_matrix (camera-to-world, OpenGL axes), intrinsics (w, h, fl_x,
// fl_y, cx, cy, or camera_angle_x) at the top level or per frame, else `reference`'s. UserError naming the file
// and the field.
std::vector<PinholeCamera> ReadCameraPath(const std::filesystem::path& file, const PinholeCamera& reference);
// Writes cameras in that layout (what ReadCameraPath reads).
void WriteCameraPath(const std::filesystem::path& file, const std::vector<PinholeCamera>& cameras);

class RenderStage : public StageOf<RenderResult> {
 public:
  // 2: renders from the splats when they are as good; 3: eval.json and render_report.json as stage_reports.h types them
  int format_version() const override { return 6; }  // 6: render.path auto by ForwardFacingCapture
  std::vector<std::string> upstream() const override {
    return {PosesResult::kId.name, TrainResult::kId.name, SplatResult::kId.name};
  }
  // Rendering the field (render.source field) reads no splats.
  std::vector<std::string> UpstreamFor(const Config& config) const override;
  std::map<std::string, std::string> ExternalInputs(const Workspace& workspace, const Config& config) const override;
  void Run(StageContext& context) const override;
};

}  // namespace p2n
