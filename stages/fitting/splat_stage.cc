#include "stages/fitting/splat_stage.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <optional>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "base/plot.h"
#include "formats/output_frame.h"
#include "formats/ply.h"
#include "nerf/renderer.h"
#include "photo2nerf/version.h"
#include "pipeline/log.h"
#include "pipeline/progress.h"
#include "splat/field_init.h"
#include "splat/scene_size.h"
#include "splat/similarity.h"
#include "splat/splat_gltf.h"
#include "splat/splat_ply.h"
#include "splat/splat_trainer.h"
#include "splat/spz.h"
#include "stages/camera_corrections.h"
#include "stages/fitting/fit_checks.h"
#include "stages/fitting/splat_optimisation.h"
#include "stages/fitting/splat_viewer.h"
#include "stages/photo_memory.h"
#include "stages/stage_io.h"
#include "stages/stage_reports.h"
#include "stages/training_data.h"
#include "stages/view_renders.h"

namespace p2n {

namespace fs = std::filesystem;

namespace {

// At most one splat per kPixelsPerSplat training pixels: small photos do not resolve more (3D Gaussian Splatting ends
// with about one per 100 to 300).
constexpr size_t kPixelsPerSplat = 64;
constexpr double kNearShare = 0.01;  // the near plane, of the cameras' extent

}  // namespace

void SplatOptions::Check() const {
  CheckField(*this, time_budget, time_budget >= 0, "must be 0 (by the preset) or positive");
  CheckField(*this, steps, steps >= 0, "must be 0 (no limit) or positive");
  CheckField(*this, sh_degree, sh_degree >= 0 && sh_degree <= kMaxShDegree, "must be 0..3");
  CheckField(*this, init_width, init_width >= 8 && init_width <= 8192, "must be 8..8192");
  CheckField(*this, max_gaussians, max_gaussians >= 1, "must be positive");
  CheckField(*this, blocks, blocks >= 1 && blocks <= 64, "must be 1..64");
  CheckField(*this, coarse, coarse >= 0 && coarse <= 1, "must be 0..1");
  CheckField(*this, max_image_size, max_image_size == 0 || max_image_size >= 16,
             "must be 0 (as they are) or at least 16 pixels");
  CheckField(*this, ssim_weight, ssim_weight >= 0 && ssim_weight <= 1, "must be 0..1");
  CheckField(*this, eval_interval, eval_interval > 0, "must be positive");
  CheckField(*this, checkpoint_interval, checkpoint_interval >= 0, "must be 0 (none) or positive");
  CheckField(*this, photo_memory, photo_memory > 0 && std::isfinite(photo_memory), "must be positive");
}

double SplatTimeBudget(const SplatOptions& options, PresetName train_preset) {
  if (options.time_budget > 0 || options.steps > 0) return options.time_budget;
  // The default preset's split between the field and the splats, and quality's 480 s: docs/benchmarks.md.
  if (train_preset == PresetName::kFast) return 30;
  return train_preset == PresetName::kQuality ? 480 : 180;
}

size_t PlacedSplats(int max_gaussians, double view_share, size_t pixels) {
  const double large = view_share < kLargeSceneShare ? kLargeSceneShare / std::max(view_share, 1e-6) : 1.0;
  return std::min(static_cast<size_t>(std::min(max_gaussians * large, 1e12)), pixels / kPixelsPerSplat);
}

SplatInit ResolveSplatInit(SplatInit init, SceneSpace space, size_t training_views, const fs::path& sparse_points) {
  if (init != SplatInit::kAuto) return init;
  if (space != SceneSpace::kUnbounded || training_views < kFewViews) return SplatInit::kField;
  const bool enough = fs::exists(sparse_points) && ReadPly(sparse_points).size() >= kMinSparseInitPoints;
  return enough ? SplatInit::kSparse : SplatInit::kField;
}

int SplatScheduleSteps(double budget) {
  const int steps = SplatTrainerOptions{}.steps;
  constexpr double kSeconds = 320;  // the budget up to which the schedule is the trainer's own
  return budget > kSeconds ? static_cast<int>(std::lround(steps * budget / kSeconds)) : steps;
}

namespace {

// The splats (in `frame`) in glTF's frame (UprightFrame: +Y up, at the scale of `frame`), their view-dependent
// colour turned with them.
Gaussians<float> UprightSplats(Gaussians<float> splats, const OutputFrame& frame) {
  const Eigen::Matrix3d linear = UprightFrame(frame).rotation * frame.rotation.inverse();
  ApplySimilarity(linear, -linear * frame.translation, &splats);
  return splats;
}

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

// The first splats (in the normalised frame) from the field or the sparse points, as many as PlacedSplats allows
// for the scene's size (measured on a first placement of as many as a small scene takes).
void PlaceSplats(const StageContext& context, const SplatOptions& options, const PosesResult& poses,
                 const TrainResult& train, const NerfModel& model, SplatSetup* setup) {
  setup->init = ResolveSplatInit(options.init, model.space, setup->data.train.size(), poses.sparse_points());
  size_t pixels = 0;
  for (const TrainView& view : setup->data.train) pixels += size_t(view.camera.width) * view.camera.height;
  std::shared_ptr<const ViewRenders> renders;
  const auto place = [&](size_t cap) {
    const FieldInitOptions init{.max_gaussians = cap, .sh_degree = options.sh_degree};
    if (setup->init == SplatInit::kSparse) return GaussiansFromSparseFile(poses.sparse_points(), init);
    if (!renders) {
      renders = RenderViewsSmall(context, train.model(), model, setup->data.train, options.init_width,
                                 "splat: placing splats from the field");
    }
    return GaussiansFromRenders(model, renders->cameras, renders->renders, init);
  };
  const size_t small = PlacedSplats(options.max_gaussians, 1, pixels);
  setup->gaussians = place(small);
  setup->view_share = MeanViewShare(setup->data.train, setup->gaussians, kNearShare * CameraExtent(setup->data.train));
  const size_t cap = PlacedSplats(options.max_gaussians, setup->view_share, pixels);
  if (cap > small) {
    LogInfo(format("splat: a training view sees {:.1f}% of the scene: up to {} splats placed", 100 * setup->view_share,
                   cap));
    setup->gaussians = place(cap);
  }
  setup->max_placed = cap;
}

// The training views of `poses` (in `setup`, their cameras as the splats see them) fitted to splat.max_image_size
// (FittedView), and SplatSetup::read_photo, which reads one from its file as it is fitted. `load`: every photo read
// now, into memory, or where they would take more than splat.photo_memory into a decoded copy in the stage's resume
// folder (SplatSetup::photos) that windows over them read. The held-out photos (kept at their size) in memory too
// where the training photos leave room enough in splat.photo_memory, else through a decoded copy (LoadHeldoutPhotos).
void LoadFittedPhotos(const StageContext& context, std::shared_ptr<const ImportedDataset> poses,
                      const SplatOptions& options, bool load, SplatSetup* setup) {
  std::vector<TrainView>& views = setup->data.train;
  const double scale = FitScale(views, options.max_image_size);
  std::vector<TrainView> full;  // without pixels
  for (TrainView& view : views) {
    full.push_back(view);
    view = FittedView(view, scale, {});
  }
  setup->read_photo = [poses, train = TrainingViews(*poses), full = std::move(full), scale](size_t v) {
    return FittedView(full[v], scale, LoadTrainView(*train[v]).pixels).pixels;
  };
  double bytes = 0;
  for (const TrainView& view : views) bytes += view.PixelBytes();
  const double memory = MegabytesToBytes(options.photo_memory);
  const std::string option = OptionKey(options, options.photo_memory);
  LoadHeldoutPhotos(*poses, options.photo_memory, option, "splat", context.resume_dir, &setup->data);
  if (!load) return;
  if (bytes <= memory) {
    Progress progress("splat: loading the training images", static_cast<int64_t>(views.size()), "images");
    tbb::parallel_for(size_t{0}, views.size(), [&](size_t v) {
      views[v].pixels = setup->read_photo(v);
      progress.Add();
    });
    setup->in_memory = true;
    return;
  }
  const WindowedPhotos windowed =
      DecodeForWindow(views, options.photo_memory, option, "splat", context.resume_dir, setup->read_photo);
  setup->views_in_memory = windowed.window;
  setup->photos = windowed.photos;
}

// The splats' world; `place`: the first splats too (a block's part begins from the whole part's instead).
SplatSetup LoadSplatSetup(const StageContext& context, const SplatOptions& options, bool place) {
  SplatSetup setup;
  const PosesResult poses_result = Upstream<PosesResult>(context);
  const TrainResult train = Upstream<TrainResult>(context);
  const TrainedField trained = ReadTrainedField(train);
  const NerfModel& model = trained.model;
  const auto dataset =
      std::make_shared<const ImportedDataset>(LoadTransformsJson(poses_result.transforms(), context.workspace.root()));
  const ImportedDataset& poses = *dataset;
  setup.data = LoadTrainingData(poses, false, /*photo_bytes=*/0);  // the training photos' pixels as they are fitted
  setup.background = model.background;
  setup.field_psnr = trained.report.heldout_psnr;
  for (TrainView& view : setup.data.train) {
    const auto found = trained.corrections.find(view.name);
    if (found != trained.corrections.end()) view.camera = CorrectedCamera(view.camera, found->second.data());
  }

  setup.gaussians.sh_degree = options.sh_degree;
  if (place) PlaceSplats(context, options, poses_result, train, model, &setup);

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
  LoadFittedPhotos(context, dataset, options, /*load=*/place, &setup);
  if (setup.data.train.front().camera.width != full_width) {
    LogInfo(format("splat: optimised on the photos at {}x{} ({} {})", setup.data.train.front().camera.width,
                   setup.data.train.front().camera.height, OptionKey(options, options.max_image_size),
                   options.max_image_size));
  }
  return setup;
}

// splat_report.json's content (but the sizes of the files written), with the signs of a failed fit.
SplatReport MakeSplatReport(const Optimised& optimised, const SplatSetup& setup, const Scores& scores, double near) {
  SplatReport report;
  report.enabled = true;
  report.splats = optimised.splats.size();
  report.initial_splats = setup.gaussians.size();
  report.view_share = setup.view_share;
  report.init = setup.init;
  report.sh_degree = optimised.splats.sh_degree;
  report.steps = optimised.steps;
  report.seconds = optimised.state.seconds;
  report.resumed_from_step = optimised.resumed_from;
  report.heldout_views = setup.data.heldout.size();
  report.training_views_in_memory = setup.views_in_memory;
  report.heldout_views_in_memory = !setup.data.read_heldout;
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

// What the stage's optimisations share: the scene, the trainer's options, the budget.
SplatRun MakeSplatRun(SplatSetup& setup, const SplatOptions& options, const StageContext& context) {
  const double near = kNearShare * setup.extent;
  const double budget = SplatTimeBudget(options, ReadOptions<TrainOptions>(context.config).preset);
  SplatRun run{setup, options, context, {&setup.data.train, setup.background, setup.extent, near}, {}, budget};
  run.scene.learn_background = options.background == SplatBackground::kAuto &&
                               FirstWithAlpha(setup.data.train) == nullptr && !setup.data.background_known;
  run.trainer.seed = static_cast<uint64_t>(options.seed);
  run.trainer.max_gaussians = 2 * std::max(setup.max_placed, static_cast<size_t>(options.max_gaussians));
  run.trainer.ssim_weight = options.ssim_weight;
  run.trainer.steps = SplatScheduleSteps(budget);
  return run;
}

}  // namespace

void SplatStage::RunPart(StageContext& context, const std::string& work, int part) const {
  if (work != kBlockWork) return Stage::RunPart(context, work, part);
  const SplatOptions options = ReadOptions<SplatOptions>(context.config);
  SplatSetup setup = LoadSplatSetup(context, options, /*place=*/false);
  OptimiseBlockAlone(MakeSplatRun(setup, options, context), part - 1);
}

void SplatStage::Run(StageContext& context) const {
  const SplatOptions options = ReadOptions<SplatOptions>(context.config);
  const SplatResult out{context.output_dir};
  if (!options.enabled) {
    WriteJsonAtomic(out.report(), SplatReport{}.ToJson());
    context.summary["splats"] = "off";
    return;
  }
  SplatSetup setup = LoadSplatSetup(context, options, /*place=*/true);
  const SplatRun run = MakeSplatRun(setup, options, context);
  const double near = run.scene.near;
  LogInfo(format("splat: {} splats placed from the {}; {} training and {} held-out views, {}", setup.gaussians.size(),
                 setup.init == SplatInit::kSparse ? "sparse points" : "field", setup.data.train.size(),
                 setup.data.heldout.size(),
                 run.budget > 0 ? format("{:.0f} s budget", run.budget) : format("{} steps", options.steps)));
  Optimised optimised = options.blocks > 1 ? OptimiseBlocks(run) : OptimiseWhole(run);

  const Scores scores = Evaluate(optimised.splats, optimised.background, setup, near, true);
  AddMetricsRow(optimised.steps, optimised.state.seconds, optimised.splats.size(), scores, &optimised.state);
  SplatReport report = MakeSplatReport(optimised, setup, scores, near);
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
