#pragma once
// The train stage: trains a radiance field on the poses stage's transforms.json and images (docs/design.md §6).
// Writes model.bin (renders without the training data), metrics.csv (wall_seconds, step, train_loss,
// heldout_psnr at fixed intervals of training time; evaluation time is not counted), train_report.json and a
// plot of held-out PSNR against time. A killed run resumes from its last checkpoint (WS/30_train.resume/).

#include <filesystem>
#include <string>

#include "formats/dataset_import.h"
#include "nerf/trainer.h"
#include "pipeline/options.h"
#include "stages/stage_results.h"
#include "stages/train_options.h"
#include "stages/train_presets.h"

namespace p2n {

// The scene space train.scene asks for; auto: bounded for Blender and .npz data, forward for a forward-facing
// capture (ForwardFacingCapture), else unbounded.
SceneSpace ResolveSceneSpace(const TrainOptions& options, const ImportedDataset& poses);

// The trainer's options for these stage options (presets resolved) in a scene of this space.
TrainerOptions MakeTrainerOptions(const TrainOptions& options, SceneSpace space);
// train.depth as a weight for a capture of `training_views` views: auto is kAutoDepth below kFewViews, else 0.
double DepthWeight(const TrainOptions& options, size_t training_views);
// The preset's time budget unless one is given.
double ResolvedTimeBudget(const TrainOptions& options);

class TrainStage : public StageOf<TrainResult> {
 public:
  // 3: photos without alpha learn the background; 4: the default preset's learning rate ends at 0.3 of its start
  // 7: train.scene auto picks forward for forward-facing captures
  // 9: bounded scenes' steps take 2^17 samples in the run's second half; 8: their hash table 2^19, occupancy 256^3
  // 10: a background the import knows stays fixed (auto); runs shorter than kShortBudget take the fast sizes
  // 11: LLFF data is forward only when its cameras face forward; 12: train.depth auto: a depth loss with few photos
  int format_version() const override { return 12; }
  std::vector<std::string> upstream() const override { return {PosesResult::kId.name}; }
  void Run(StageContext& context) const override;
  // Block `part` (from 1) of train.blocks (stages/train_blocks.h).
  void RunPart(StageContext& context, const std::string& work, int part) const override;
};

}  // namespace p2n
