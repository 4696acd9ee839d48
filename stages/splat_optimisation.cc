#include "stages/splat_optimisation.h"

#include <chrono>
#include <optional>

#include "base/binary_io.h"
#include "base/format.h"
#include "nerf/renderer.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "splat/blocks.h"
#include "stages/stage_io.h"
#include "stages/stage_results.h"

namespace p2n {

namespace fs = std::filesystem;

Scores Evaluate(const Gaussians<float>& gaussians, const std::array<float, 3>& background, const SplatSetup& setup,
                double near, bool with_ssim) {
  Scores scores;
  double seconds = 0;
  for (const TrainView& view : setup.data.heldout) {
    ThrowIfCancelled();
    const auto start = std::chrono::steady_clock::now();
    const FloatImage image = RenderSplats(gaussians, view.camera, background, near);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const FloatImage photo = PhotoOnBackground(view, background);
    scores.psnr.push_back(Psnr(image, photo));
    if (with_ssim) scores.ssim.push_back(Ssim(image, photo));
  }
  scores.seconds_per_view = scores.psnr.empty() ? 0 : seconds / scores.psnr.size();
  return scores;
}

void AddMetricsRow(int steps, double seconds, size_t splats, const Scores& scores, RunState* state) {
  const double loss = state->TakeMeanLoss(0);
  state->metrics += format("{:.3f},{},{},{:.6g},{:.4f}\n", seconds, steps, splats, loss, Mean(scores.psnr));
}

namespace {

// The steps and seconds of the parts optimised before the one at hand (their metrics rows go on from there).
struct Earlier {
  int steps = 0;
  double seconds = 0;
};

// A part of the optimisation: its share of the run (from, to: of the budget, of densification's schedule) and the
// trainer's step when it begins.
struct Part {
  double from = 0, to = 1;
  int start_step = 0;
};

// Optimises on `views` until the part's share of the budget (seconds, else steps) is spent: a metrics row at every
// evaluation but the last (the caller's final evaluation makes it), checkpoints in `checkpoint`.
void OptimiseUntilDone(const SplatRun& run, SplatTrainer& trainer, const std::vector<TrainView>& views,
                       const fs::path& checkpoint, const Earlier& earlier, const Part& part, RunState* state) {
  const SplatOptions& options = run.options;
  const double width = part.to - part.from;
  const int steps = options.steps > 0 ? std::max(1, static_cast<int>(std::lround(options.steps * width))) : 0;
  const RunLoop loop{SplatResult::kId.name,      run.budget * width, steps, options.eval_interval, 1, false,
                     options.checkpoint_interval};
  const std::vector<TrainView> coarse = options.coarse > 0 ? HalfSizeViews(views) : std::vector<TrainView>{};
  const auto step = [&](double share) -> std::optional<double> {
    const double progress = part.from + share * width;
    trainer.SetViews(!coarse.empty() && progress < options.coarse ? &coarse : &views);
    trainer.SetProgress(progress);
    return trainer.Step();
  };
  const auto add_row = [&](RunState* now) {
    const Gaussians<float> drawn = trainer.Drawn();
    const Scores scores = Evaluate(drawn, trainer.background(), run.setup, run.scene.near, false);
    AddMetricsRow(earlier.steps + trainer.step() - part.start_step, earlier.seconds + now->seconds, drawn.size(),
                  scores, now);
  };
  const auto save = [&](const RunState& now) {
    WriteOrExplain(
        [&] { SaveRunCheckpoint(checkpoint, run.context.key, now, [&](BinaryWriter* w) { trainer.Save(w); }); });
  };
  loop.Run(
      state, [&] { return trainer.step() - part.start_step; }, step, add_row, save);
}

// Optimises with `trainer` on `views` for `part` of the run, resuming from `checkpoint` where it holds this run;
// saves one there at the end when `checkpoint_at_end`.
Optimised OptimisePart(const SplatRun& run, SplatTrainer& trainer, const std::vector<TrainView>& views,
                       const fs::path& checkpoint, const Earlier& earlier, const Part& part, bool checkpoint_at_end) {
  Optimised out;
  const std::string& key = run.context.key;
  const bool resumed =
      LoadRunCheckpoint(checkpoint, key, SplatResult::kId.name, &out.state, [&](BinaryReader* r) { trainer.Load(r); });
  out.resumed_from = resumed ? trainer.step() - part.start_step : 0;
  if (out.resumed_from > 0) LogInfo(format("splat: resumed at step {} from {}", trainer.step(), checkpoint.string()));
  OptimiseUntilDone(run, trainer, views, checkpoint, earlier, part, &out.state);
  if (checkpoint_at_end && run.options.checkpoint_interval > 0) {
    WriteOrExplain([&] { SaveRunCheckpoint(checkpoint, key, out.state, [&](BinaryWriter* w) { trainer.Save(w); }); });
  }
  out.splats = trainer.gaussians();
  out.background = trainer.background();
  out.steps = trainer.step() - part.start_step;
  return out;
}

// The share of the run the splats are optimised whole before the blocks go on from there: the other blocks, drawn
// as they are then, must already look like the scene (drawn as they started, they pull each block's splats into
// making up for them, and the merge is much worse; docs/benchmarks.md).
constexpr double kWholeShare = 0.5;
// The training views seen by a block when at least this share of the splats they show are the block's.
constexpr double kBlockViewShare = 0.1;

// Adds `part`'s steps, seconds, metrics rows and loss to `total`.
void AddPart(const Optimised& part, Optimised* total) {
  total->steps += part.steps;
  total->resumed_from += part.resumed_from;
  total->state.metrics += part.state.metrics;
  total->state.seconds += part.state.seconds;
  total->state.loss_sum += part.state.loss_sum;
  total->state.loss_steps += part.state.loss_steps;
}

}  // namespace

Optimised OptimiseWhole(const SplatRun& run) {
  SplatTrainer trainer(run.setup.gaussians, run.scene, run.trainer);
  return OptimisePart(run, trainer, run.setup.data.train, CheckpointFile(run.context), {}, {}, false);
}

Optimised OptimiseBlocks(const SplatRun& run) {
  const SplatSetup& setup = run.setup;
  SplatTrainer whole(setup.gaussians, run.scene, run.trainer);
  Optimised total = OptimisePart(run, whole, setup.data.train, CheckpointFile(run.context), {}, {0, kWholeShare}, true);
  const Gaussians<float>& start = whole.gaussians();
  const SplatBlocks blocks = CutIntoBlocks(start, run.options.blocks);
  LogInfo(format("splat: {} blocks across the {} axis, each optimised from here for the rest of the budget",
                 blocks.count(), "xyz"[blocks.axis]));
  BinaryWriter where_whole_ended;
  whole.Save(&where_whole_ended);
  std::vector<Gaussians<float>> optimised;
  std::array<double, 3> background{0, 0, 0};
  for (int b = 0; b < blocks.count(); ++b) {
    const Gaussians<float> others = SplatsOfBlock(start, blocks, b, false);
    std::vector<TrainView> views;
    for (const size_t v : ViewsOfBlock(setup.data.train, start, blocks, b, kBlockViewShare, run.scene.near))
      views.push_back(setup.data.train[v]);
    std::vector<bool> keep(start.size());
    for (size_t i = 0; i < start.size(); ++i) keep[i] = blocks.BlockOf(&start.positions[3 * i]) == b;
    LogInfo(format("splat: block {} of {}: {} splats, {} training views", b + 1, blocks.count(),
                   start.size() - others.size(), views.size()));
    Optimised block;
    block.splats = SplatsOfBlock(start, blocks, b, true);
    block.background = whole.background();
    if (block.splats.size() > 0 && !views.empty()) {
      SplatTrainer trainer(start, run.scene, run.trainer);  // where the whole part ended
      BinaryReader reader(where_whole_ended.buffer(), "the splats optimised whole");
      trainer.Load(&reader);
      trainer.Restrict(keep, &others, &views);
      const fs::path checkpoint = run.context.resume_dir / format("checkpoint_block{}.bin", b + 1);
      block = OptimisePart(run, trainer, views, checkpoint, {total.steps, total.state.seconds},
                           {kWholeShare, 1, whole.step()}, true);
    }
    optimised.push_back(std::move(block.splats));
    for (int c = 0; c < 3; ++c) background[c] += block.background[c] / blocks.count();
    AddPart(block, &total);
  }
  total.splats = MergeBlocks(optimised);
  for (int c = 0; c < 3; ++c) total.background[c] = static_cast<float>(background[c]);
  return total;
}

}  // namespace p2n
