#pragma once
// The export stage: a mesh of the trained scene's surface (marching cubes on the density inside the scene box, or
// in an unbounded scene the part of it the views look at; coloured from the field), a coloured point cloud from the
// rendered depth of the training views, and the cameras (transforms.json, the training ones as camera refinement left
// them), in COLMAP's (or the dataset's) world frame or the normalised one; binary PLY (and OBJ when asked).

#include <string>
#include <vector>

#include "stages/outputs/export_options.h"
#include "stages/stage_results.h"

namespace p2n {

class ExportStage : public StageOf<ExportResult> {
 public:
  // 5: the point cloud rendered at most 2 M pixels; 6: at the median depth (the splat stage's renders); 7: the mesh
  // simplified, mesh.glb and its texture; 8: from at most 200 training views
  int format_version() const override { return 8; }
  std::vector<std::string> upstream() const override { return {PosesResult::kId.name, TrainResult::kId.name}; }
  void Run(StageContext& context) const override;
};

}  // namespace p2n
