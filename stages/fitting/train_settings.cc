#include "stages/fitting/train_settings.h"

#include <cmath>
#include <optional>

#include "base/format.h"
#include "nerf/ngp_field.h"
#include "nerf/vanilla_field.h"
#include "stages/training_data.h"

namespace p2n {

// A forward-facing capture trains in normalised device coordinates: fewer samples a ray and a better fit than
// contracted space (docs/benchmarks.md, training options).
SceneSpace ResolveSceneSpace(const TrainOptions& options, const ImportedDataset& poses) {
  switch (options.scene) {
    case SceneChoice::kBounded:
      return SceneSpace::kBounded;
    case SceneChoice::kUnbounded:
      return SceneSpace::kUnbounded;
    case SceneChoice::kForward:
      return SceneSpace::kForward;
    case SceneChoice::kAuto:
      break;
  }
  const std::optional<DatasetKind> kind = poses.meta.dataset_kind;
  if (kind == DatasetKind::kBlender || kind == DatasetKind::kNpz) return SceneSpace::kBounded;
  return ForwardFacingCapture(poses) ? SceneSpace::kForward : SceneSpace::kUnbounded;
}

void TrainOptions::Check() const {
  CheckField(*this, time_budget, time_budget >= 0, "must be 0 (the preset's) or positive");
  CheckField(*this, steps, steps >= 0, "must be 0 (no limit) or positive");
  CheckField(*this, batch_samples, batch_samples >= 0 && batch_samples <= (1 << 24), "must be 0..16777216");
  CheckField(*this, march_samples, march_samples >= 0 && march_samples <= 8192, "must be 0..8192");
  CheckField(*this, hash_table_log2, hash_table_log2 == 0 || (hash_table_log2 >= 10 && hash_table_log2 <= 24),
             "must be 0 (the preset's) or 10..24");
  for (const int* resolution : {&plane_resolution, &plane_depth_resolution}) {
    CheckField(*this, *resolution, *resolution == 0 || (*resolution >= 8 && *resolution <= 8192),
               "must be 0 (by the scene) or 8..8192");
  }
  CheckField(*this, vanilla_samples, vanilla_samples >= 1 && vanilla_samples <= 1024, "must be 1..1024");
  CheckField(*this, learning_rate, learning_rate >= 0 && learning_rate < 1, "must be 0 (the field's) or in (0, 1)");
  CheckField(*this, distortion, !distortion.value || *distortion.value >= 0,
             format("must be auto or a weight >= 0, not {}", AutoOrNumberText(distortion)));
  CheckField(*this, depth, !depth.value || (*depth.value >= 0 && std::isfinite(*depth.value)),
             format("must be auto or a weight >= 0, not {}", AutoOrNumberText(depth)));
  CheckField(*this, refine_cameras, !refine_cameras || field != FieldKind::kVanilla,
             format("needs {} ngp or planes (the vanilla field has no gradient with respect to its input)",
                    OptionKey(*this, field)));
  CheckField(*this, eval_interval, eval_interval > 0, "must be positive");
  CheckField(*this, eval_share, eval_share > 0 && eval_share <= 1, "must be in (0, 1]");
  CheckField(*this, eval_pixels, eval_pixels >= 0, "must be 0 (all) or positive");
  CheckField(*this, final_eval_pixels, final_eval_pixels >= 0, "must be 0 (all) or positive");
  CheckField(*this, checkpoint_interval, checkpoint_interval >= 0, "must be 0 (none) or positive");
  CheckField(*this, photo_memory, photo_memory > 0 && std::isfinite(photo_memory), "must be positive");
  CheckField(*this, blocks, blocks >= 1 && blocks <= 64, "must be 1..64");
}

double ResolvedTimeBudget(const TrainOptions& options) {
  if (options.time_budget > 0) return options.time_budget;
  return options.steps > 0 ? 0.0 : PresetFor(options.preset).time_budget;
}

// train.distortion as a weight: auto is kAutoDistortion where space reaches past the box, 0 in a bounded scene.
double DistortionWeight(const TrainOptions& options, SceneSpace space) {
  const std::optional<double>& weight = options.distortion.value;
  return weight ? *weight : space != SceneSpace::kBounded ? kAutoDistortion : 0.0;
}

double DepthWeight(const TrainOptions& options, size_t training_views) {
  const std::optional<double>& weight = options.depth.value;
  return weight ? *weight : training_views < kFewViews ? kAutoDepth : 0.0;
}

TrainerOptions MakeTrainerOptions(const TrainOptions& options, SceneSpace space) {
  const TrainPreset preset = PresetForBudget(options.preset, ResolvedTimeBudget(options));
  TrainerOptions trainer;
  const bool vanilla = options.field == FieldKind::kVanilla;
  if (vanilla) {
    trainer.field = VanillaFieldConfig{}.ToJson();
    trainer.stratified_samples = options.vanilla_samples;
  } else {
    NgpFieldConfig field;
    field.grid = preset.grid;
    if (space == SceneSpace::kBounded && preset.bounded_table_log2 > 0)
      field.grid.log2_table_size = preset.bounded_table_log2;
    if (options.hash_table_log2 > 0) field.grid.log2_table_size = options.hash_table_log2;
    if (options.field == FieldKind::kPlanes) {
      field.planes = PlanesFor(space);
      if (options.plane_resolution > 0) field.planes->finest_resolution = options.plane_resolution;
      if (options.plane_depth_resolution > 0) field.planes->depth_resolution = options.plane_depth_resolution;
    }
    trainer.field = field.ToJson();
  }
  const int march = options.march_samples > 0       ? options.march_samples
                    : space != SceneSpace::kBounded ? kUnboundedMarchSamples
                                                    : preset.march_samples;
  trainer.march_step = 2 * std::sqrt(3.0) / march;  // the scene box [-1, 1]^3's diagonal
  if (!vanilla && options.march_samples == 0 && space == SceneSpace::kBounded && preset.fine_march_samples > 0)
    trainer.fine_march_step = 2 * std::sqrt(3.0) / preset.fine_march_samples;
  trainer.occupancy_resolution = preset.occupancy_resolution;
  if (space == SceneSpace::kBounded && preset.bounded_occupancy_resolution > 0)
    trainer.occupancy_resolution = preset.bounded_occupancy_resolution;
  trainer.batch_samples = options.batch_samples > 0 ? options.batch_samples : preset.batch_samples;
  if (options.batch_samples == 0 && space == SceneSpace::kBounded)
    trainer.late_batch_samples = preset.bounded_late_batch_samples;
  trainer.learning_rate = options.learning_rate > 0 ? options.learning_rate : vanilla ? 5e-4 : 1e-2;
  trainer.final_learning_rate = trainer.learning_rate * (vanilla ? 0.1 : kNgpFinalLearningRate);
  trainer.loss = options.loss;
  trainer.space = space;
  trainer.distortion_weight = DistortionWeight(options, space);
  trainer.appearance = options.appearance;
  trainer.refine_cameras = options.refine_cameras;
  trainer.error_sampling = options.error_sampling;
  trainer.seed = static_cast<uint64_t>(options.seed);
  return trainer;
}

}  // namespace p2n
