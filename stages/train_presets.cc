#include "stages/train_presets.h"

namespace p2n {

TrainPreset PresetFor(const std::string& name) {
  if (name == "fast") return {60, 128, 0, 1 << 15, 64, {16, 2, 15, 16, 1024}};
  // Measured at lego 800 (5-minute runs): 8 levels of 4 features (half the table reads of 16 levels of 2, the
  // same encoding width) train 19% more steps and reach +0.25 dB. At 5 minutes it beats the default on lego (29.60
  // against 28.22 dB), not on the real captures (fox 27.10 against 28.41, fern 22.39 against 22.53, with 128 samples
  // unbounded).
  if (name == "quality") return {900, 512, 0, 1 << 17, 128, {8, 4, 19, 16, 4096}};
  // 240 s, and the splats 180 (splat stage): on the Zen 3 that split gave fox's splats 26.41 and 27.24 dB against
  // 25.99 and 25.72 after 300 + 120 s (the field 25.00 and 25.14 against 25.20), fern's 23.19 and 23.13 against
  // 23.06 (the field 21.81 and 21.72 against 21.98), in the same wall time: the splats are what the render stage
  // and the viewer show.
  // Bounded scenes march 256 samples, 512 from the 1,000th step on: a young field's haze costs rays at the finer
  // spacing, a grown one gains detail (one thread each, side by side; lego 800: 600 s 29.34 against 28.34 dB, 4.7
  // samples a ray rendered against 3.0; 512 throughout: 300 s 28.35 and 28.30 against 27.77, 60 s 22.28 against
  // 22.94; lego_200, 40 s: 512 throughout 0.4-1.3 dB lower, 128 0.9-1.2 lower; 300 s 512 30.87 against 30.79).
  // Lego 800, 5 minutes alone on two threads: 29.11 dB (4,713 steps) against 28.31 with 256 throughout.
  // Bounded scenes' hash table has 2^19 entries a level, real captures' 2^17: lego 800, 5 minutes alone on two
  // threads, 30.03 dB (5,986 steps) against 29.92 with 2^18 (6,584) and 29.68 with 2^17 (7,629); 600 s on one
  // thread each, side by side, 29.98 against 29.80 (6,097 and 7,938 steps). Fox loses by it, the same pair 28.18
  // against 28.90 (5,419 and 6,728 steps): a step costs a fifth more, and a real capture is short of steps, not of
  // entries (fern at equal steps: 2^19 +0.2 dB, at equal time level).
  // Bounded scenes' occupancy grid has 256 cells a side, real captures' 128: with 2^19 entries, lego 800's 600 s
  // pair 30.48 against 30.09 dB (4,690 steps against 6,565: each 16th step refreshes a sixteenth of eight times the
  // cells), 4.3 samples a ray rendered against 5.2; fox's pair 28.69 against 28.93 (5,239 steps against 6,654).
  // Lego 800 alone on two threads with both: 30.52 dB after 5 minutes (4,417 steps), 31.88 after 15 (13,456).
  // Bounded scenes' steps take 2^17 samples in the run's second half: lego 800, 1,800 s on one thread each side by
  // side (15 minutes' worth), 32.02 against 31.83 dB (9,501 steps against 13,089), 3.9 samples a ray rendered
  // against 4.2; 2^17 throughout lost its 600 s pair, 30.53 against 30.65 (3,229 steps against 4,951).
  return {240, 256, 512, 1 << 16, 128, {16, 2, 17, 16, 2048}, 19, 256, 1 << 17};
}

TrainPreset PresetForBudget(const std::string& name, double budget) {
  if (budget <= 0 || budget >= kShortBudget) return PresetFor(name);
  TrainPreset preset = PresetFor("fast");
  preset.time_budget = budget;
  return preset;
}

}  // namespace p2n
