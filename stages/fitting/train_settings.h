#pragma once
// What the train stage's options resolve to: the scene space, the time budget, the loss weights chosen by the
// capture, and the trainer's options (the presets resolved; stages/fitting/train_presets.h).

#include <cstddef>

#include "formats/dataset_import.h"
#include "nerf/trainer.h"
#include "stages/fitting/train_options.h"
#include "stages/fitting/train_presets.h"

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

}  // namespace p2n
