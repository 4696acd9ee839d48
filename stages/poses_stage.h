#pragma once
// The poses stage: the sfm stage's (undistorted) COLMAP model to camera-to-world matrices in OpenGL axes and
// pinhole intrinsics, normalised so that the scene fits the unit cube, with per-view near/far bounds and a
// held-out split. Writes transforms.json (readable by instant-ngp and nerfstudio) and sparse_points.ply.

#include "pipeline/stage.h"

namespace p2n {

struct PosesOptions {
  int holdout_every = 8;  // every Nth view (in name order) is held out for evaluation; 0 holds out none
  bool normalize = true;  // centre, rotate (up = +z) and scale the scene into the unit cube

  template <class V>
  void Visit(V& v) {
    v("holdout_every", holdout_every, "every Nth view is held out for evaluation; 0: none", "views");
    v("normalize", normalize, "centre, turn upright and scale the scene into the unit cube");
  }
  void Check() const;
};

class PosesStage : public Stage {
 public:
  std::string name() const override { return "poses"; }
  std::string folder() const override { return "20_poses"; }
  int format_version() const override { return 1; }
  std::vector<std::string> upstream() const override { return {"sfm"}; }
  void Run(StageContext& context) const override;
};

}  // namespace p2n
