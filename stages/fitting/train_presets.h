#pragma once
// The train stage's presets (train.preset: fast, default, quality) and the settings it picks by the scene, each
// chosen by measurement (docs/benchmarks.md, the presets).

#include "base/enum_names.h"
#include "nerf/encoding.h"
#include "nerf/nerf_model.h"
#include "nerf/plane_grid.h"

namespace p2n {

enum class PresetName { kFast, kDefault, kQuality };
template <>
struct EnumNames<PresetName> {
  static constexpr std::pair<PresetName, const char*> kValues[] = {
      {PresetName::kFast, "fast"}, {PresetName::kDefault, "default"}, {PresetName::kQuality, "quality"}};
};

// train.distortion auto in unbounded and forward scenes.
inline constexpr double kAutoDistortion = 0.002;

// train.depth auto for captures of fewer than kFewViews training views (with sparse tracks), and 0 otherwise.
inline constexpr double kAutoDepth = 1.0;

// The planes (train.field planes) for a scene space, in every preset.
PlaneGridConfig PlanesFor(SceneSpace space);

struct TrainPreset {
  double time_budget;      // seconds
  int march_samples;       // across the box's diagonal, bounded scenes (unbounded and forward: kUnboundedMarchSamples)
  int fine_march_samples;  // bounded scenes from the trainer's fine_march_from (1,000th) step on; 0: march_samples
  int batch_samples, occupancy_resolution;
  HashGridConfig grid;  // levels, features per level, log2 table size, base and finest resolution
  // Bounded scenes' log2 table size and occupancy grid resolution; 0: the grid's and occupancy_resolution.
  int bounded_table_log2 = 0, bounded_occupancy_resolution = 0;
  // Bounded scenes' samples per step in the run's second half; 0: batch_samples throughout.
  int bounded_late_batch_samples = 0;
};

TrainPreset PresetFor(PresetName name);

// Runs shorter than this many seconds train with the fast preset's sizes, whichever preset is named: the larger
// table, grid and batches of the others pay after minutes, and cost a short run the steps it needs to get out of
// its first haze (docs/benchmarks.md, short budgets).
inline constexpr double kShortBudget = 45;
// The settings of preset `name` for a run of `budget` seconds (0: a run by steps, the preset's own).
TrainPreset PresetForBudget(PresetName name, double budget);

// ngp's learning rate ends at 0.3 of its start rather than a tenth, in every preset: each underfits at its end.
inline constexpr double kNgpFinalLearningRate = 0.3;

// Unbounded and forward scenes march with 128 samples across the box's diagonal in every preset (near the
// centre; the step grows with the distance beyond it; docs/benchmarks.md, the presets).
inline constexpr int kUnboundedMarchSamples = 128;

}  // namespace p2n
