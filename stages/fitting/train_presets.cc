#include "stages/fitting/train_presets.h"

namespace p2n {

TrainPreset PresetFor(PresetName name) {
  if (name == PresetName::kFast) return {60, 128, 0, 1 << 15, 64, {16, 2, 15, 16, 1024}};
  // 8 levels of 4 features: half the table reads of 16 levels of 2 for the same encoding width.
  if (name == PresetName::kQuality) return {900, 512, 0, 1 << 17, 128, {8, 4, 19, 16, 4096}};
  // 240 s (the splats 180: the splat stage). Bounded scenes march 256 samples and 512 from the 1,000th step on,
  // with 2^19 table entries a level, an occupancy grid of 256 cells a side and 2^17 samples a step in the run's
  // second half; real captures, short of steps rather than of entries, keep 2^17 entries and 128 cells. Why each:
  // docs/benchmarks.md, the presets.
  return {240, 256, 512, 1 << 16, 128, {16, 2, 17, 16, 2048}, 19, 256, 1 << 17};
}

PlaneGridConfig PlanesFor(SceneSpace space) {
  PlaneGridConfig planes;
  // Forward-facing: 256 cells across the image plane, 64 in depth (fern, 2 minutes of the default preset: above
  // 512 x 512 and 256 x 256, which take fewer steps; docs/benchmarks.md, the planes).
  planes.finest_resolution = 256;
  planes.depth_resolution = space == SceneSpace::kForward ? 64 : 256;
  return planes;
}

TrainPreset PresetForBudget(PresetName name, double budget) {
  if (budget <= 0 || budget >= kShortBudget) return PresetFor(name);
  TrainPreset preset = PresetFor(PresetName::kFast);
  preset.time_budget = budget;
  return preset;
}

}  // namespace p2n
