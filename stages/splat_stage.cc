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

// A metrics.csv row: the run so far, the training loss since the last row and the held-out PSNR.
void AddMetricsRow(const SplatTrainer& trainer, const Scores& scores, RunState* state) {
  const double loss = state->TakeMeanLoss(0);
  state->metrics += format("{:.3f},{},{},{:.6g},{:.4f}\n", state->seconds, trainer.step(), trainer.gaussians().size(),
                           loss, Mean(scores.psnr));
}

// Optimises until the budget (seconds, else steps) is spent: a metrics row at every evaluation but the last (the
// caller's final evaluation makes it), checkpoints.
void OptimiseUntilDone(SplatTrainer& trainer, const SplatSetup& setup, const SplatOptions& options, double budget,
                       double near, const fs::path& checkpoint, const std::string& key, RunState* state) {
  const RunLoop loop{SplatResult::kId.name,      budget, options.steps, options.eval_interval, 1, false,
                     options.checkpoint_interval};
  const std::vector<TrainView> coarse = options.coarse > 0 ? HalfSizeViews(setup.data.train) : std::vector<TrainView>{};
  const auto step = [&](double share) -> std::optional<double> {
    trainer.SetViews(!coarse.empty() && share < options.coarse ? &coarse : &setup.data.train);
    trainer.SetProgress(share);
    return trainer.Step();
  };
  const auto add_row = [&](RunState* run) {
    AddMetricsRow(trainer, Evaluate(trainer.gaussians(), trainer.background(), setup, near, false), run);
  };
  const auto save = [&](const RunState& run) {
    WriteOrExplain([&] { SaveRunCheckpoint(checkpoint, key, run, [&](BinaryWriter* w) { trainer.Save(w); }); });
  };
  loop.Run(
      state, [&] { return trainer.step(); }, step, add_row, save);
}

}  // namespace

// splat_report.json's content (but the sizes of the files written), with the signs of a failed fit.
SplatReport MakeSplatReport(const SplatTrainer& trainer, const SplatSetup& setup, const SplatOptions& options,
                            const Scores& scores, double seconds, int resumed_from, double near) {
  SplatReport report;
  report.enabled = true;
  report.splats = trainer.gaussians().size();
  report.initial_splats = setup.gaussians.size();
  report.init = EnumName(options.init);
  report.sh_degree = trainer.gaussians().sh_degree;
  report.steps = trainer.step();
  report.seconds = seconds;
  report.resumed_from_step = resumed_from;
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
  report.background = trainer.background();
  report.warnings = CheckSplatFit(HeldoutViewFits(setup.data, scores.psnr), report.heldout_psnr, setup.field_psnr);
  return report;
}

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
  SplatTrainer trainer(setup.gaussians, scene, trainer_options);
  RunState state;
  const fs::path checkpoint = CheckpointFile(context);
  const bool resumed =
      LoadRunCheckpoint(checkpoint, context.key, name(), &state, [&](BinaryReader* r) { trainer.Load(r); });
  const int resumed_from = resumed ? trainer.step() : 0;
  if (resumed_from > 0) LogInfo(format("splat: resumed at step {} from {}", resumed_from, checkpoint.string()));
  OptimiseUntilDone(trainer, setup, options, budget, near, checkpoint, context.key, &state);

  const Scores scores = Evaluate(trainer.gaussians(), trainer.background(), setup, near, true);
  AddMetricsRow(trainer, scores, &state);
  WriteOrExplain([&] {
    WriteSplatPly(out.splats(), trainer.gaussians(),
                  {setup.frame.description,
                   format("{} splats of SH degree {}", trainer.gaussians().size(), trainer.gaussians().sh_degree)});
  });
  WriteOrExplain([&] {
    const std::vector<char> spz = SpzBytes(trainer.gaussians());
    WriteFileAtomic(out.spz(), std::string_view(spz.data(), spz.size()));
  });
  WriteOrExplain([&] {
    WriteFileAtomic(out.glb(), SplatGlbBytes(UprightSplats(trainer.gaussians(), setup.frame),
                                             "photo2nerf " + std::string(kVersion)));
  });
  size_t viewer_bytes = 0;
  WriteOrExplain([&] {
    fs::path root = context.workspace.root().lexically_normal();
    if (!root.has_filename()) root = root.parent_path();  // "ws/" -> "ws"
    const std::string scene = root.filename().string();
    viewer_bytes = WriteSplatViewer(out.viewer(), "photo2nerf: " + scene, trainer.gaussians(), setup.data, setup.frame,
                                    trainer.background(), near);
  });
  const std::string metrics = "wall_seconds,step,splats,train_loss,heldout_psnr\n" + state.metrics;
  WriteFileAtomic(out.metrics(), metrics);
  const PlotSeries curve = CsvSeries("held-out PSNR", metrics, 0, 4);
  if (!curve.x.empty()) {
    WriteOrExplain([&] {
      WriteLinePlot(out.psnr_plot(), {"splats: held-out PSNR against optimisation time", "time (s)", "PSNR (dB)"},
                    {curve});
    });
  }
  SplatReport report = MakeSplatReport(trainer, setup, options, scores, state.seconds, resumed_from, near);
  report.file_bytes = fs::file_size(out.splats());
  report.spz_bytes = fs::file_size(out.spz());
  report.glb_bytes = fs::file_size(out.glb());
  report.viewer_bytes = viewer_bytes;
  WriteJsonAtomic(out.report(), report.ToJson());
  context.summary["splats"] = trainer.gaussians().size();
  if (!setup.data.heldout.empty()) context.summary["splat_psnr"] = Mean(scores.psnr);
  LogInfo(format("splat: {} splats, held-out PSNR {:.2f} dB, {:.3f} s per held-out view", trainer.gaussians().size(),
                 Mean(scores.psnr), scores.seconds_per_view));
  LogFitWarnings(SplatResult::kId.name, report.warnings);
}

}  // namespace p2n
