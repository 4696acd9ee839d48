#pragma once
// The train stage: trains a radiance field on the poses stage's transforms.json and images (docs/design.md §6).
// Writes model.bin (renders without the training data), metrics.csv (wall_seconds, step, train_loss,
// heldout_psnr at fixed intervals of training time; evaluation time is not counted), train_report.json and a
// plot of held-out PSNR against time. A killed run resumes from its last checkpoint (WS/30_train.resume/).

#include <filesystem>
#include <string>

#include "stages/stage_results.h"

namespace p2n {

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
  // Block `part` (from 1) of train.blocks (stages/fitting/train_blocks.h).
  void RunPart(StageContext& context, const std::string& work, int part) const override;
};

}  // namespace p2n
