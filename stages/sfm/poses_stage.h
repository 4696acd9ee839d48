#pragma once
// The poses stage: the sfm stage's (undistorted) COLMAP model to camera-to-world matrices in OpenGL axes and
// pinhole intrinsics, normalised so that the scene fits the unit cube, with per-view near/far bounds and a
// held-out split. Writes transforms.json (readable by instant-ngp and nerfstudio) and sparse_points.ply, and
// copies of the images larger than poses.max_image_size (downsized) or with a mask (with alpha) in images/; the
// others are named where they are.

#include "stages/sfm/poses_options.h"
#include "stages/stage_results.h"

namespace p2n {

class PosesStage : public StageOf<PosesResult> {
 public:
  // 2: images downsized to poses.max_image_size; 3: fewer than 20 photos hold out views inside the span of the others
  // 4: sparse_tracks.json; 5: the photos' masks as alpha
  int format_version() const override { return 5; }
  std::vector<std::string> upstream() const override { return {SfmResult::kId.name}; }
  void Run(StageContext& context) const override;
};

}  // namespace p2n
