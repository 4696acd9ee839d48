#include "stages/fitting/splat_optimisation.h"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "base/binary_io.h"
#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "nerf/renderer.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "splat/blocks.h"
#include "splat/splat_schedule.h"
#include "stages/fitting/blocked_run.h"
#include "stages/photo_memory.h"
#include "stages/stage_io.h"
#include "stages/stage_results.h"
#include "stages/training_data.h"

namespace p2n {

namespace fs = std::filesystem;

Scores Evaluate(const Gaussians<float>& gaussians, const std::array<float, 3>& background, const SplatSetup& setup,
                double near, bool with_ssim) {
  Scores scores;
  double seconds = 0;
  for (size_t v = 0; v < setup.data.heldout.size(); ++v) {
    ThrowIfCancelled();
    TrainView scratch;
    const TrainView& view = HeldoutView(setup.data, v, &scratch);
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

// The training views an optimisation runs on: the setup's, or some of them (a block's, or all where the setup does not
// hold them) borrowed or read (BorrowViews).
struct ViewsInUse {
  const std::vector<TrainView>* views = nullptr;
  std::vector<TrainView> own;
  BorrowedViews borrowed;  // into `own`, which outlives it
};

// The training views `indices` without their pixels.
std::vector<TrainView> Cameras(const SplatRun& run, const std::vector<size_t>& indices) {
  std::vector<TrainView> views;
  for (const size_t v : indices) views.push_back(WithoutPixels(run.setup.data.train[v]));
  return views;
}

// The training views `indices` (none: all of them) with their pixels, or a window over them, into `use`.
void UseViews(const SplatRun& run, std::optional<std::vector<size_t>> indices, ViewsInUse* use) {
  SplatSetup& setup = run.setup;
  if (!indices && setup.in_memory) {
    use->views = &setup.data.train;
    return;
  }
  if (!indices) {
    indices.emplace(setup.data.train.size());
    std::iota(indices->begin(), indices->end(), size_t{0});
  }
  const PhotoWindow::Loader read = [&setup](size_t v) {
    return setup.photos ? setup.photos->Read(v) : setup.read_photo(v);
  };
  const PhotoSource source{read,
                           setup.photos,
                           MegabytesToBytes(run.options.photo_memory),
                           static_cast<uint64_t>(run.options.seed),
                           run.context.resume_dir,
                           "splat: decoding the block's photos"};
  BorrowViews(&setup.data.train, *indices, source, &use->own, &use->borrowed);
  use->views = &use->own;
}

// Optimises on `use`'s views until the part's share of the budget (seconds, else steps) is spent: a metrics row (its
// steps and seconds the part's own) at every evaluation but the last (the caller's final evaluation makes it),
// checkpoints in `checkpoint`. With a window over the views, each step draws from those it holds then.
void OptimiseUntilDone(const SplatRun& run, SplatTrainer& trainer, const ViewsInUse& use, const fs::path& checkpoint,
                       const BudgetPart& part, RunState* state) {
  const SplatOptions& options = run.options;
  const double width = part.share();
  const int steps = options.steps > 0 ? std::max(1, static_cast<int>(std::lround(options.steps * width))) : 0;
  const RunLoop loop{SplatResult::kId.name,      run.budget * width, steps, options.eval_interval, 1, false,
                     options.checkpoint_interval};
  SplatSchedule schedule(&trainer, use.views, use.borrowed.window.get(), options.coarse, run.setup.data.train.size());
  const auto step = [&](double share) { return schedule.Step(part.from + share * width); };
  const auto add_row = [&](RunState* now) {
    const Gaussians<float> drawn = trainer.Drawn();
    const Scores scores = Evaluate(drawn, trainer.background(), run.setup, run.scene.near, false);
    AddMetricsRow(trainer.step() - part.start_step, now->seconds, drawn.size(), scores, now);
  };
  const auto save = [&](const RunState& now) {
    WriteOrExplain(
        [&] { SaveRunCheckpoint(checkpoint, run.context.key, now, [&](BinaryWriter* w) { trainer.Save(w); }); });
  };
  loop.Run(
      state, [&] { return trainer.step() - part.start_step; }, step, add_row, save);
}

// Optimises with `trainer` on `use`'s views for `part` of the run, resuming from `checkpoint` where it holds this run;
// saves one there at the end when `checkpoint_at_end` (the next part begins from it).
Optimised OptimisePart(const SplatRun& run, SplatTrainer& trainer, const ViewsInUse& use, const fs::path& checkpoint,
                       const BudgetPart& part, bool checkpoint_at_end) {
  Optimised out;
  const std::string& key = run.context.key;
  const bool resumed =
      LoadRunCheckpoint(checkpoint, key, SplatResult::kId.name, &out.state, [&](BinaryReader* r) { trainer.Load(r); });
  out.resumed_from = resumed ? trainer.step() - part.start_step : 0;
  if (out.resumed_from > 0) LogInfo(format("splat: resumed at step {} from {}", trainer.step(), checkpoint.string()));
  OptimiseUntilDone(run, trainer, use, checkpoint, part, &out.state);
  if (checkpoint_at_end) {
    WriteOrExplain([&] { SaveRunCheckpoint(checkpoint, key, out.state, [&](BinaryWriter* w) { trainer.Save(w); }); });
  }
  out.splats = trainer.gaussians();
  out.background = trainer.background();
  out.steps = trainer.step() - part.start_step;
  return out;
}

// `rows` (metrics.csv rows: seconds, step, then the rest) moved on by `seconds` and `steps`.
std::string ShiftRows(const std::string& rows, int steps, double seconds) {
  std::istringstream lines(rows);
  std::string line, shifted;
  while (std::getline(lines, line)) {
    const size_t first = line.find(','), second = line.find(',', first + 1);
    if (second == std::string::npos) throw std::logic_error("ShiftRows: a metrics row without its fields: " + line);
    shifted += format("{:.3f},{}{}\n", std::stod(line.substr(0, first)) + seconds,
                      std::stoi(line.substr(first + 1, second - first - 1)) + steps, line.substr(second));
  }
  return shifted;
}

// Adds `part` (made after the parts in `total`) to `total`: its steps and seconds, its metrics rows moved on by
// those of `total`, its loss.
void AddPart(const Optimised& part, Optimised* total) {
  total->state.metrics += ShiftRows(part.state.metrics, total->steps, total->state.seconds);
  total->steps += part.steps;
  total->resumed_from += part.resumed_from;
  total->state.seconds += part.state.seconds;
  total->state.loss_sum += part.state.loss_sum;
  total->state.loss_steps += part.state.loss_steps;
}

// Where every block begins: the trainer as the whole part left it, its splats cut into blocks.
struct BlocksStart {
  BinaryWriter trainer;
  Gaussians<float> splats;
  std::array<float, 3> background{1, 1, 1};
  int step = 0;
  Slabs blocks;
};

BlocksStart StartOfBlocks(const SplatTrainer& whole, int count) {
  BlocksStart start;
  whole.Save(&start.trainer);
  start.splats = whole.gaussians();
  start.background = whole.background();
  start.step = whole.step();
  start.blocks = CutIntoSlabs(Means(start.splats), count);
  return start;
}

// Block b's part: its splats optimised from where the whole part ended for the rest of the budget, on the views that
// see it, the other splats its context (resuming from its own checkpoint); the result in its checkpoint.
void OptimiseBlock(const SplatRun& run, const BlocksStart& start, int b) {
  std::vector<bool> keep = InSlab(start.splats, start.blocks, b);
  const size_t splats = std::count(keep.begin(), keep.end(), true);
  std::vector<size_t> seeing = ViewsOfSlab(run.setup.data.train, start.splats, start.blocks, b, run.scene.near);
  LogInfo(format("splat: block {} of {}: {} splats, {} training views", b + 1, start.blocks.count(), splats,
                 seeing.size()));
  if (splats == 0) seeing.clear();
  int resumed_from = 0;
  if (!seeing.empty()) {
    ViewsInUse use;
    UseViews(run, seeing, &use);
    Gaussians<float> others = start.splats;
    keep.flip();
    others.Filter(keep);
    keep.flip();
    SplatTrainer trainer(start.splats, run.scene, run.trainer);
    BinaryReader reader(start.trainer.buffer(), "the splats optimised whole");
    trainer.Load(&reader);
    trainer.Restrict(keep, &others, use.views);
    BudgetPart part = kBlockPart;
    part.start_step = start.step;
    resumed_from = OptimisePart(run, trainer, use, BlockCheckpoint(run.context, b), part, true).resumed_from;
  }
  MarkBlockDone(run.context, b, {{"resumed_from", resumed_from}, {"views", seeing}});
}

// What block b's finished part made, from its checkpoint; `earlier`: it finished before this run of the stage (its
// steps count as resumed from).
Optimised BlockResult(const SplatRun& run, const BlocksStart& start, int b, bool earlier) {
  const nlohmann::json done = FinishedBlock(run.context, SplatResult::kId.name, b);
  Optimised out;
  out.background = start.background;
  const std::vector<size_t> seeing = done.value("views", std::vector<size_t>{});
  if (seeing.empty()) {  // not optimised: the block's splats as the whole part left them
    out.splats = start.splats;
    out.splats.Filter(InSlab(start.splats, start.blocks, b));
    return out;
  }
  const std::vector<TrainView> views = Cameras(run, seeing);
  SplatScene scene = run.scene;
  scene.views = &views;
  Gaussians<float> none;
  none.sh_degree = start.splats.sh_degree;
  SplatTrainer trainer(none, scene, run.trainer);  // all of it read from the checkpoint
  if (!LoadRunCheckpoint(BlockCheckpoint(run.context, b), run.context.key, SplatResult::kId.name, &out.state,
                         [&](BinaryReader* r) { trainer.Load(r); })) {
    throw ExternalToolError(format("splat: block {}'s result {} is missing or not this run's; run the stage again",
                                   b + 1, BlockCheckpoint(run.context, b).string()));
  }
  out.splats = trainer.gaussians();
  out.background = trainer.background();
  out.steps = trainer.step() - start.step;
  out.resumed_from = earlier ? out.steps : done.value("resumed_from", 0);
  return out;
}

}  // namespace

Optimised OptimiseWhole(const SplatRun& run) {
  SplatTrainer trainer(run.setup.gaussians, run.scene, run.trainer);
  ViewsInUse use;
  UseViews(run, std::nullopt, &use);
  return OptimisePart(run, trainer, use, CheckpointFile(run.context), {}, run.options.checkpoint_interval > 0);
}

Optimised OptimiseBlocks(const SplatRun& run) {
  SplatTrainer whole(run.setup.gaussians, run.scene, run.trainer);
  Optimised total;
  {
    ViewsInUse use;  // let go before the blocks read theirs
    UseViews(run, std::nullopt, &use);
    AddPart(OptimisePart(run, whole, use, CheckpointFile(run.context), kWholePart, true), &total);
  }
  const BlocksStart start = StartOfBlocks(whole, run.options.blocks);
  LogInfo(format("splat: {} blocks across the {} axis, each optimised from here for the rest of the budget",
                 start.blocks.count(), "xyz"[start.blocks.axis]));
  SaveBlocksStart(run.context, nlohmann::json::object(), run.setup.data.train);
  const std::vector<int> ran =
      RunPendingBlocks(run.context, start.blocks.count(), [&](int b) { OptimiseBlock(run, start, b); });

  std::vector<Gaussians<float>> optimised;
  std::array<double, 3> background{0, 0, 0};
  for (int b = 0; b < start.blocks.count(); ++b) {
    const bool earlier = std::find(ran.begin(), ran.end(), b) == ran.end();
    Optimised block = BlockResult(run, start, b, earlier);
    for (int c = 0; c < 3; ++c) background[c] += block.background[c] / start.blocks.count();
    AddPart(block, &total);
    optimised.push_back(std::move(block.splats));
  }
  total.splats = MergeSlabs(optimised);
  for (int c = 0; c < 3; ++c) total.background[c] = static_cast<float>(background[c]);
  return total;
}

void OptimiseBlockAlone(const SplatRun& run, int b) {
  const std::string stage = SplatResult::kId.name;
  BlocksStartOfJob(run.context, stage, b, run.setup.data.train, Upstream<PosesResult>(run.context).transforms());
  SplatTrainer whole(run.setup.gaussians, run.scene, run.trainer);
  RunState state;
  LoadWholePart(run.context, stage, b, &state, [&](BinaryReader* r) { whole.Load(r); });
  const BlocksStart start = StartOfBlocks(whole, run.options.blocks);
  CheckBlockIndex(stage, b, start.blocks.count());
  OptimiseBlock(run, start, b);
}

}  // namespace p2n
