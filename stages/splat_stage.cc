#include "stages/splat_stage.h"

#include <chrono>
#include <cmath>
#include <optional>

#include "base/binary_io.h"
#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "formats/output_frame.h"
#include "formats/ply.h"
#include "nerf/plot.h"
#include "nerf/renderer.h"
#include "photo2nerf/version.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "splat/blocks.h"
#include "splat/field_init.h"
#include "splat/similarity.h"
#include "splat/splat_gltf.h"
#include "splat/splat_ply.h"
#include "splat/splat_trainer.h"
#include "splat/spz.h"
#include "stages/camera_corrections.h"
#include "stages/fit_checks.h"
#include "stages/splat_viewer.h"
#include "stages/stage_io.h"
#include "stages/stage_reports.h"
#include "stages/timed_run.h"
#include "stages/train_stage.h"
#include "stages/training_data.h"
#include "stages/view_renders.h"

namespace p2n {

namespace fs = std::filesystem;

void SplatOptions::Check() const {
  CheckOption(*this, time_budget, time_budget >= 0, "must be 0 (by the preset) or positive");
  CheckOption(*this, steps, steps >= 0, "must be 0 (no limit) or positive");
  CheckOption(*this, sh_degree, sh_degree >= 0 && sh_degree <= kMaxShDegree, "must be 0..3");
  CheckOption(*this, init_width, init_width >= 8 && init_width <= 8192, "must be 8..8192");
  CheckOption(*this, max_gaussians, max_gaussians >= 1, "must be positive");
  CheckOption(*this, blocks, blocks >= 1 && blocks <= 64, "must be 1..64");
  CheckOption(*this, coarse, coarse >= 0 && coarse <= 1, "must be 0..1");
  CheckOption(*this, max_image_size, max_image_size == 0 || max_image_size >= 16,
              "must be 0 (as they are) or at least 16 pixels");
  CheckOption(*this, ssim_weight, ssim_weight >= 0 && ssim_weight <= 1, "must be 0..1");
  CheckOption(*this, eval_interval, eval_interval > 0, "must be positive");
  CheckOption(*this, checkpoint_interval, checkpoint_interval >= 0, "must be 0 (none) or positive");
}

double SplatTimeBudget(const SplatOptions& options, PresetName train_preset) {
  if (options.time_budget > 0 || options.steps > 0) return options.time_budget;
  // The default preset's split between the field and the splats, and quality's 480 s: docs/benchmarks.md.
  if (train_preset == PresetName::kFast) return 30;
  return train_preset == PresetName::kQuality ? 480 : 180;
}

namespace {

constexpr size_t kPixelsPerSplat = 64;

// The splats (in `frame`) in glTF's frame (UprightFrame: +Y up, at the scale of `frame`), their view-dependent
// colour turned with them.
Gaussians<float> UprightSplats(Gaussians<float> splats, const OutputFrame& frame) {
  const Eigen::Matrix3d linear = UprightFrame(frame).rotation * frame.rotation.inverse();
  ApplySimilarity(linear, -linear * frame.translation, &splats);
  return splats;
}

// The splats' world: the training data with every camera in the output frame (the training views as camera
// refinement left them), the first Gaussians there, and the scene's extent.
struct SplatSetup {
  TrainingData data;
  OutputFrame frame;
  Gaussians<float> gaussians;
  std::array<float, 3> background{1, 1, 1};
  double extent = 1;
  std::optional<double> field_psnr;  // the field's held-out PSNR, as the train stage measured it
};

// 1.1 times the largest distance of a training camera from their mean (3D Gaussian Splatting's scene radius).
double CameraExtent(const std::vector<TrainView>& views) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const TrainView& v : views) mean += v.camera.world_from_cam.topRightCorner<3, 1>();
  mean /= static_cast<double>(views.size());
  double radius = 0;
  for (const TrainView& v : views)
    radius = std::max(radius, (v.camera.world_from_cam.topRightCorner<3, 1>() - mean).norm());
  return 1.1 * std::max(radius, 1e-6);
}

// 3D Gaussian Splatting's start from the poses stage's sparse points (normalised frame); UserError when there are
// none (a dataset imported with its cameras has none).
Gaussians<float> GaussiansFromSparseFile(const fs::path& file, const FieldInitOptions& init) {
  const std::vector<ColouredPoint> cloud = fs::exists(file) ? ReadPly(file) : std::vector<ColouredPoint>{};
  if (cloud.empty()) {
    throw UserError(
        format("{0} sparse: '{1}' has no points (a dataset imported with its cameras has none); use --{0} field",
               OptionKey(&SplatOptions::init), file.string()));
  }
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3f> rgb;
  for (const ColouredPoint& p : cloud) {
    points.push_back(p.position.cast<double>());
    rgb.emplace_back(p.rgb[0] / 255.0f, p.rgb[1] / 255.0f, p.rgb[2] / 255.0f);
  }
  return GaussiansFromSparsePoints(points, rgb, init.max_gaussians, init.sh_degree);
}

SplatSetup LoadSplatSetup(const StageContext& context, const SplatOptions& options) {
  SplatSetup setup;
  const PosesResult poses_result = Upstream<PosesResult>(context);
  const TrainResult train = Upstream<TrainResult>(context);
  const TrainedField trained = ReadTrainedField(train);
  const NerfModel& model = trained.model;
  const ImportedDataset poses = LoadTransformsJson(poses_result.transforms(), context.workspace.root());
  setup.data = LoadTrainingData(poses);
  setup.background = model.background;
  setup.field_psnr = trained.report.heldout_psnr;
  for (TrainView& view : setup.data.train) {
    const auto found = trained.corrections.find(view.name);
    if (found != trained.corrections.end()) view.camera = CorrectedCamera(view.camera, found->second.data());
  }

  FieldInitOptions init;
  // At most one splat per kPixelsPerSplat training pixels: small photos do not resolve more (3D Gaussian
  // Splatting ends with about one per 100 to 300).
  size_t pixels = 0;
  for (const TrainView& view : setup.data.train) pixels += size_t(view.camera.width) * view.camera.height;
  init.max_gaussians = std::min(static_cast<size_t>(options.max_gaussians), pixels / kPixelsPerSplat);
  init.sh_degree = options.sh_degree;
  if (options.init == SplatInit::kSparse) {
    setup.gaussians = GaussiansFromSparseFile(poses_result.sparse_points(), init);
  } else {
    const std::shared_ptr<const ViewRenders> renders = RenderViewsSmall(
        context, train.model(), model, setup.data.train, options.init_width, "splat: placing splats from the field");
    setup.gaussians = GaussiansFromRenders(model, renders->cameras, renders->renders, init);
  }

  setup.frame = MakeOutputFrame(options.frame, poses);
  if (setup.frame.rotation.determinant() <= 0) {
    LogWarning("splat: the source frame is mirrored; splats.ply is written in the normalised frame");
    setup.frame = MakeOutputFrame(FrameKind::kNormalized, poses);
  }
  ApplySimilarity(setup.frame.rotation, setup.frame.translation, &setup.gaussians);
  for (auto* views : {&setup.data.train, &setup.data.heldout}) {
    for (TrainView& view : *views) view.camera.world_from_cam = setup.frame.Pose(view.camera.world_from_cam);
  }
  setup.extent = CameraExtent(setup.data.train);
  // Large photos are optimised downsized (splat.max_image_size): more steps on fewer pixels score better at full
  // size (docs/benchmarks.md, splats).
  const int full_width = setup.data.train.front().camera.width;
  setup.data.train = FittedViews(setup.data.train, options.max_image_size);
  if (setup.data.train.front().camera.width != full_width) {
    LogInfo(format("splat: optimised on the photos at {}x{} ({} {})", setup.data.train.front().camera.width,
                   setup.data.train.front().camera.height, OptionKey(options, options.max_image_size),
                   options.max_image_size));
  }
  return setup;
}

// PSNR and SSIM of the splats on every held-out view (the same during the run as at its end, so that the curve
// ends at the reported score).
struct Scores {
  std::vector<double> psnr, ssim;
  double seconds_per_view = 0;
};
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

// A metrics.csv row: the run so far (`earlier`: the steps and seconds of the blocks optimised before this one), the
// splats drawn, the training loss since the last row and the held-out PSNR.
struct Earlier {
  int steps = 0;
  double seconds = 0;
};
void AddMetricsRow(int step, size_t splats, const Scores& scores, const Earlier& earlier, RunState* state) {
  const double loss = state->TakeMeanLoss(0);
  state->metrics += format("{:.3f},{},{},{:.6g},{:.4f}\n", earlier.seconds + state->seconds, earlier.steps + step,
                           splats, loss, Mean(scores.psnr));
}

// Optimises on `views` until the budget (seconds, else steps) is spent: a metrics row at every evaluation but the last
// (the caller's final evaluation makes it), checkpoints in `checkpoint`.
void OptimiseUntilDone(SplatTrainer& trainer, const std::vector<TrainView>& views, const SplatSetup& setup,
                       const SplatOptions& options, double budget, double near, const fs::path& checkpoint,
                       const std::string& key, const Earlier& earlier, RunState* state) {
  const RunLoop loop{SplatResult::kId.name,      budget, options.steps, options.eval_interval, 1, false,
                     options.checkpoint_interval};
  const std::vector<TrainView> coarse = options.coarse > 0 ? HalfSizeViews(views) : std::vector<TrainView>{};
  const auto step = [&](double share) -> std::optional<double> {
    trainer.SetViews(!coarse.empty() && share < options.coarse ? &coarse : &views);
    trainer.SetProgress(share);
    return trainer.Step();
  };
  const auto add_row = [&](RunState* run) {
    const Gaussians<float> drawn = trainer.Drawn();
    AddMetricsRow(trainer.step(), drawn.size(), Evaluate(drawn, trainer.background(), setup, near, false), earlier,
                  run);
  };
  const auto save = [&](const RunState& run) {
    WriteOrExplain([&] { SaveRunCheckpoint(checkpoint, key, run, [&](BinaryWriter* w) { trainer.Save(w); }); });
  };
  loop.Run(
      state, [&] { return trainer.step(); }, step, add_row, save);
}

// What the optimisation made: the splats, the colour behind them, its steps (every block's), the steps a resumed run
// started from, and its state (every block's metrics rows, its seconds summed).
struct Optimised {
  Gaussians<float> splats;
  std::array<float, 3> background{1, 1, 1};
  int steps = 0, resumed_from = 0;
  RunState state;
};

// Optimises `splats` on `views` (with `scene.context` drawn), resuming from `checkpoint` where it holds this run.
Optimised OptimiseSplats(const Gaussians<float>& splats, const std::vector<TrainView>& views, SplatScene scene,
                         const SplatTrainerOptions& trainer_options, const SplatSetup& setup,
                         const SplatOptions& options, const StageContext& context, double budget,
                         const fs::path& checkpoint, const Earlier& earlier, bool checkpoint_at_end) {
  scene.views = &views;
  SplatTrainer trainer(splats, scene, trainer_options);
  Optimised out;
  const bool resumed = LoadRunCheckpoint(checkpoint, context.key, SplatResult::kId.name, &out.state,
                                         [&](BinaryReader* r) { trainer.Load(r); });
  out.resumed_from = resumed ? trainer.step() : 0;
  if (out.resumed_from > 0) {
    LogInfo(format("splat: resumed at step {} from {}", out.resumed_from, checkpoint.string()));
  }
  OptimiseUntilDone(trainer, views, setup, options, budget, scene.near, checkpoint, context.key, earlier, &out.state);
  if (checkpoint_at_end && options.checkpoint_interval > 0) {
    WriteOrExplain(
        [&] { SaveRunCheckpoint(checkpoint, context.key, out.state, [&](BinaryWriter* w) { trainer.Save(w); }); });
  }
  out.splats = trainer.gaussians();
  out.background = trainer.background();
  out.steps = trainer.step();
  return out;
}

// The training views seen by a block when at least this share of the splats they show are the block's.
constexpr double kBlockViewShare = 0.1;

// Optimises each of options.blocks slabs in turn (splat/blocks.h), each for the whole budget, with its checkpoint
// kept when it ends so that a resumed run goes on with the next; merges them.
Optimised OptimiseBlocks(const SplatScene& scene, const SplatTrainerOptions& trainer_options, const SplatSetup& setup,
                         const SplatOptions& options, const StageContext& context, double budget) {
  const SplatBlocks blocks = CutIntoBlocks(setup.gaussians, options.blocks);
  LogInfo(
      format("splat: {} blocks across the {} axis, each optimised for the budget", blocks.count(), "xyz"[blocks.axis]));
  std::vector<Gaussians<float>> optimised;
  Optimised merged;
  merged.background = {0, 0, 0};
  Earlier earlier;
  for (int b = 0; b < blocks.count(); ++b) {
    Gaussians<float> own = SplatsOfBlock(setup.gaussians, blocks, b, true);
    const Gaussians<float> others = SplatsOfBlock(setup.gaussians, blocks, b, false);
    std::vector<TrainView> views;
    for (const size_t v : ViewsOfBlock(setup.data.train, setup.gaussians, blocks, b, kBlockViewShare, scene.near))
      views.push_back(setup.data.train[v]);
    LogInfo(
        format("splat: block {} of {}: {} splats, {} training views", b + 1, blocks.count(), own.size(), views.size()));
    SplatScene block_scene = scene;
    block_scene.context = &others;
    Optimised block;
    block.splats = own;
    block.background = scene.background;
    if (own.size() > 0 && !views.empty()) {
      const fs::path checkpoint = context.resume_dir / format("checkpoint_block{}.bin", b + 1);
      SplatTrainerOptions block_options = trainer_options;
      block_options.seed += static_cast<uint64_t>(b);
      block = OptimiseSplats(own, views, block_scene, block_options, setup, options, context, budget, checkpoint,
                             earlier, true);
    }
    optimised.push_back(std::move(block.splats));
    for (int c = 0; c < 3; ++c) merged.background[c] += block.background[c] / blocks.count();
    merged.steps += block.steps;
    merged.resumed_from += block.resumed_from;
    merged.state.metrics += block.state.metrics;
    merged.state.seconds += block.state.seconds;
    merged.state.loss_sum += block.state.loss_sum;
    merged.state.loss_steps += block.state.loss_steps;
    earlier = {merged.steps, merged.state.seconds};
  }
  merged.splats = MergeBlocks(optimised);
  return merged;
}

// splat_report.json's content (but the sizes of the files written), with the signs of a failed fit.
SplatReport MakeSplatReport(const Optimised& optimised, const SplatSetup& setup, const SplatOptions& options,
                            const Scores& scores, double near) {
  SplatReport report;
  report.enabled = true;
  report.splats = optimised.splats.size();
  report.initial_splats = setup.gaussians.size();
  report.init = EnumName(options.init);
  report.sh_degree = optimised.splats.sh_degree;
  report.steps = optimised.steps;
  report.seconds = optimised.state.seconds;
  report.resumed_from_step = optimised.resumed_from;
  report.heldout_views = setup.data.heldout.size();
  if (!setup.data.heldout.empty()) {
    report.heldout_psnr = Mean(scores.psnr);
    report.heldout_ssim = Mean(scores.ssim);
  }
  report.heldout_psnr_per_view = scores.psnr;
  report.seconds_per_view = scores.seconds_per_view;
  report.frame = setup.frame.kind;
  report.frame_description = setup.frame.description;
  report.near = near;
  report.background = optimised.background;
  report.warnings = CheckSplatFit(HeldoutViewFits(setup.data, scores.psnr), report.heldout_psnr, setup.field_psnr);
  return report;
}

// splats.ply, .spz, .glb, viewer.html, metrics.csv and the PSNR plot; the report's file sizes filled in.
void WriteSplatFiles(const SplatResult& out, const Optimised& optimised, const SplatSetup& setup,
                     const StageContext& context, double near, SplatReport* report) {
  const Gaussians<float>& splats = optimised.splats;
  WriteOrExplain([&] {
    WriteSplatPly(out.splats(), splats,
                  {setup.frame.description, format("{} splats of SH degree {}", splats.size(), splats.sh_degree)});
  });
  WriteOrExplain([&] {
    const std::vector<char> spz = SpzBytes(splats);
    WriteFileAtomic(out.spz(), std::string_view(spz.data(), spz.size()));
  });
  WriteOrExplain([&] {
    WriteFileAtomic(out.glb(),
                    SplatGlbBytes(UprightSplats(splats, setup.frame), "photo2nerf " + std::string(kVersion)));
  });
  WriteOrExplain([&] {
    fs::path root = context.workspace.root().lexically_normal();
    if (!root.has_filename()) root = root.parent_path();  // "ws/" -> "ws"
    const std::string scene = root.filename().string();
    report->viewer_bytes = WriteSplatViewer(out.viewer(), "photo2nerf: " + scene, splats, setup.data, setup.frame,
                                            optimised.background, near);
  });
  const std::string metrics = "wall_seconds,step,splats,train_loss,heldout_psnr\n" + optimised.state.metrics;
  WriteFileAtomic(out.metrics(), metrics);
  const PlotSeries curve = CsvSeries("held-out PSNR", metrics, 0, 4);
  if (!curve.x.empty()) {
    WriteOrExplain([&] {
      WriteLinePlot(out.psnr_plot(), {"splats: held-out PSNR against optimisation time", "time (s)", "PSNR (dB)"},
                    {curve});
    });
  }
  report->file_bytes = fs::file_size(out.splats());
  report->spz_bytes = fs::file_size(out.spz());
  report->glb_bytes = fs::file_size(out.glb());
}

}  // namespace

void SplatStage::Run(StageContext& context) const {
  const SplatOptions options = ReadOptions<SplatOptions>(context.config);
  const SplatResult out{context.output_dir};
  if (!options.enabled) {
    WriteJsonAtomic(out.report(), SplatReport{}.ToJson());
    context.summary["splats"] = "off";
    return;
  }
  const TrainOptions train_options = ReadOptions<TrainOptions>(context.config);
  const double budget = SplatTimeBudget(options, train_options.preset);
  const SplatSetup setup = LoadSplatSetup(context, options);
  const double near = 0.01 * setup.extent;
  LogInfo(format("splat: {} splats placed from the {}; {} training and {} held-out views, {}", setup.gaussians.size(),
                 options.init == SplatInit::kSparse ? "sparse points" : "field", setup.data.train.size(),
                 setup.data.heldout.size(),
                 budget > 0 ? format("{:.0f} s budget", budget) : format("{} steps", options.steps)));

  SplatTrainerOptions trainer_options;
  trainer_options.seed = static_cast<uint64_t>(options.seed);
  trainer_options.max_gaussians = 2 * static_cast<size_t>(options.max_gaussians);
  trainer_options.ssim_weight = options.ssim_weight;
  SplatScene scene{&setup.data.train, setup.background, setup.extent, near};
  scene.learn_background = options.background == SplatBackground::kAuto &&
                           FirstWithAlpha(setup.data.train) == nullptr && !setup.data.background_known;
  Optimised optimised = options.blocks > 1
                            ? OptimiseBlocks(scene, trainer_options, setup, options, context, budget)
                            : OptimiseSplats(setup.gaussians, setup.data.train, scene, trainer_options, setup, options,
                                             context, budget, CheckpointFile(context), Earlier{}, false);

  const Scores scores = Evaluate(optimised.splats, optimised.background, setup, near, true);
  AddMetricsRow(optimised.steps, optimised.splats.size(), scores, Earlier{}, &optimised.state);
  SplatReport report = MakeSplatReport(optimised, setup, options, scores, near);
  WriteSplatFiles(out, optimised, setup, context, near, &report);
  WriteJsonAtomic(out.report(), report.ToJson());
  context.summary["splats"] = optimised.splats.size();
  if (options.blocks > 1) context.summary["splat_blocks"] = options.blocks;
  if (!setup.data.heldout.empty()) context.summary["splat_psnr"] = Mean(scores.psnr);
  LogInfo(format("splat: {} splats, held-out PSNR {:.2f} dB, {:.3f} s per held-out view", optimised.splats.size(),
                 Mean(scores.psnr), scores.seconds_per_view));
  LogFitWarnings(SplatResult::kId.name, report.warnings);
}

}  // namespace p2n
