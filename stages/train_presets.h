#pragma once
// The train stage's presets (train.preset: fast, default, quality) and the settings it picks by the scene, each
// chosen by measurement: the figures are beside each (the presets' in train_presets.cc).

#include <string>

#include "nerf/encoding.h"

namespace p2n {

// train.distortion auto in an unbounded scene. Fox and fern, 2 minutes of the default preset: weight 0.002
// +0.7 and +0.5 dB and fewer samples per ray than 0 (fern 210 -> 137); 0.01 -4.1 and -0.9 dB.
inline constexpr double kAutoDistortion = 0.002;

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

// The preset of that name (train.preset; its options have been checked): default for any other.
TrainPreset PresetFor(const std::string& name);

// Runs shorter than this many seconds train with the fast preset's sizes, whichever preset is named: the larger
// table, grid and batches of the others pay after minutes, and cost a short run the steps it needs to get out of
// its first haze (docs/benchmarks.md, short budgets).
inline constexpr double kShortBudget = 45;
// The settings of preset `name` for a run of `budget` seconds (0: a run by steps, the preset's own).
TrainPreset PresetForBudget(const std::string& name, double budget);

// ngp's learning rate ends at 0.3 of its start rather than a tenth, in every preset: each underfits at its end.
// One thread per run, two runs side by side: the default (300 s, about 2,000 steps) fox 27.09 against 26.27 dB,
// lego 27.68 against 27.45, fern 21.96 and 22.02 against 21.79; 600 s (4,300 to 4,700 steps, as 5 minutes on two
// threads) fox 28.37 against 28.08 (9.2 samples a ray against 10.1), lego 28.35 against 28.19. A constant rate:
// fox +0.4, lego and fern -0.05 against 0.3. The fast preset (60 s): lego_200 26.43 and 26.38 against 25.78 and
// 25.62, fox 24.59 against 23.30 (22.6 samples a ray against 27.8). The quality preset: +0.25 dB at lego 800.
inline constexpr double kNgpFinalLearningRate = 0.3;

// Unbounded and forward scenes march with 128 samples across the box's diagonal in every preset (near the
// centre; the step grows with the distance beyond it). Fox and fern, 5 minutes of the default preset (session 12,
// `bench/train_bench.sh DATASET 300 OUT default -- --train.eval_interval 60 --train.march_samples N`):
// 64 samples 26.61 / 22.26 dB, 128 28.41 / 22.53, 256 27.70 / 22.72, 512 - / 22.33; fox renders 6.5, 10.0 and
// 20.1 samples per ray. (At 2 minutes of a 2.5x slower engine, session 8, 64 had been best: fewer samples per
// ray bought more rays while the young field was haze.) The demo's scene with the fast preset (60 s): 128
// 22.27 dB, 64 21.69, 32 20.97. 256 from the 1,000th step on (one thread each, 600 s, side by side): fox 28.93
// against 28.14 dB, but 16.7 samples a ray rendered against 9.3, so no finer march for these scenes.
inline constexpr int kUnboundedMarchSamples = 128;

}  // namespace p2n
