#pragma once
// The splat stage's optimisation (stages/fitting/splat_stage.cc): the splats optimised whole, or block by block
// (splat.blocks: stages/fitting/blocked_run.h, splat/blocks.h), until the budget is spent, with held-out evaluations as
// metrics.csv rows and checkpoints that a killed run resumes from.

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "base/decoded_photos.h"
#include "base/photo_window.h"
#include "base/posed_image.h"
#include "formats/output_frame.h"
#include "pipeline/stage.h"
#include "splat/gaussians.h"
#include "splat/splat_trainer.h"
#include "stages/fitting/splat_options.h"
#include "stages/fitting/timed_run.h"

namespace p2n {

// The splats' world: the training data with every camera in the output frame (the training views as camera
// refinement left them), the first Gaussians there, and the scene's extent.
struct SplatSetup {
  TrainingData data;
  OutputFrame frame;
  Gaussians<float> gaussians;
  std::array<float, 3> background{1, 1, 1};
  double extent = 1;
  std::optional<double> field_psnr;  // the field's held-out PSNR, as the train stage measured it
  // Where the splats were placed (not in a block's part job, whose trainer takes its cap from the whole part's
  // checkpoint): the mean share of them a training view sees (splat/scene_size.h), and the most placed
  // (PlacedSplats; densification may double it or splat.max_gaussians, whichever is more).
  double view_share = 1;
  size_t max_placed = 0;
  SplatInit init = SplatInit::kField;  // where they were placed from (splat.init resolved)
  // Training view v's pixels, fitted to splat.max_image_size, read from its file. Where the training photos would
  // take more than splat.photo_memory, `data` holds none of them: `photos` is their decoded copy, which windows over
  // them read (none in a block's job, which reads its block's photos alone), and `views_in_memory` the whole
  // optimisation's window's size.
  PhotoWindow::Loader read_photo;
  std::shared_ptr<const DecodedPhotos> photos;
  std::optional<size_t> views_in_memory;
  bool in_memory = false;  // `data` holds every training photo (borrowed by a block's part while it runs)
};

// What every optimisation of one stage run shares.
struct SplatRun {
  // Changed by nothing but a block's part run here, which borrows the training photos' pixels from it and gives
  // them back (UseViews in splat_optimisation.cc): the parts run in turn.
  SplatSetup& setup;
  const SplatOptions& options;
  const StageContext& context;
  SplatScene scene;  // the training views, the background, the extent and the near plane
  SplatTrainerOptions trainer;
  double budget = 0;  // seconds each trainer optimises for; 0: options.steps
};

// What the optimisation made: the splats, the colour behind them, its steps (every block's), the steps a resumed run
// started from, and its state (every block's metrics rows, their seconds summed).
struct Optimised {
  Gaussians<float> splats;
  std::array<float, 3> background{1, 1, 1};
  int steps = 0, resumed_from = 0;
  RunState state;
};

// The whole scene's splats optimised at once, resuming from the stage's checkpoint.
Optimised OptimiseWhole(const SplatRun& run);
// The splats' run by blocks (stages/fitting/blocked_run.h): optimised whole, then each of options.blocks slabs of them
// on from there on the views that see it, the other splats drawn as the whole left them; merged.
Optimised OptimiseBlocks(const SplatRun& run);
// Block b's part alone (in a job of its own), from the whole part's checkpoint.
void OptimiseBlockAlone(const SplatRun& run, int b);

// PSNR and SSIM of the splats on every held-out view (the same during the run as at its end, so that the curve
// ends at the reported score).
struct Scores {
  std::vector<double> psnr, ssim;
  double seconds_per_view = 0;
};
Scores Evaluate(const Gaussians<float>& gaussians, const std::array<float, 3>& background, const SplatSetup& setup,
                double near, bool with_ssim);

// Appends the metrics.csv row of `splats` after `steps` (every block's) and the run's seconds: the training loss
// since the last row and the held-out PSNR.
void AddMetricsRow(int steps, double seconds, size_t splats, const Scores& scores, RunState* state);

}  // namespace p2n
