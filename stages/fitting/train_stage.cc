#include "stages/fitting/train_stage.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/float_image.h"
#include "base/format.h"
#include "base/plot.h"
#include "formats/dataset_import.h"
#include "nerf/appearance.h"
#include "nerf/ngp_field.h"
#include "nerf/renderer.h"
#include "nerf/vanilla_field.h"
#include "pipeline/log.h"
#include "stages/camera_corrections.h"
#include "stages/fitting/fit_checks.h"
#include "stages/fitting/timed_run.h"
#include "stages/fitting/train_blocks.h"
#include "stages/fitting/train_presets.h"
#include "stages/fitting/train_settings.h"
#include "stages/stage_io.h"
#include "stages/stage_reports.h"
#include "stages/training_data.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

// Training views scored at the end beside the held-out ones (spread over them).
constexpr size_t kTrainingViewsScored = 8;

// The finished field's scores: each held-out view's PSNR (and NeRF-W's fitted one), some training views', the cost
// of rendering the held-out pixels, and what the held-out photos show where rays end on nothing.
struct FinalEvaluation {
  std::vector<double> heldout, fitted, training;
  RenderStats stats;
  BehindScene behind;
};

// The per-photo colour transforms (train_report.json's "appearance").
TrainReport::Appearance AppearanceReport(const Trainer& trainer, const TrainingData& data) {
  TrainReport::Appearance appearance;
  const std::vector<float>& params = trainer.appearance();
  if (params.empty()) return appearance;
  appearance.enabled = true;
  std::vector<double> gains;
  for (size_t v = 0; v < data.train.size(); ++v) {
    const float* transform = &params[v * kAppearanceParams];
    gains.push_back(AppearanceGain(transform));
    appearance.per_view.push_back(
        {data.train[v].name, gains.back(), std::vector<float>(transform, transform + kAppearanceParams)});
  }
  appearance.gain_min = *std::min_element(gains.begin(), gains.end());
  appearance.gain_max = *std::max_element(gains.begin(), gains.end());
  return appearance;
}

TrainReport MakeTrainReport(Trainer& trainer, const TrainerOptions& trainer_options, const TrainOptions& options,
                            const TrainingData& data, const FinalEvaluation& evaluation, int resumed_from,
                            const SessionLog& session) {
  const std::vector<double>& psnrs = evaluation.heldout;
  const RenderStats& eval_stats = evaluation.stats;
  TrainReport report;
  report.steps = trainer.step();
  report.skipped_steps = trainer.skipped_steps();
  report.resumed_from_step = resumed_from;
  report.training_views = data.train.size();
  report.heldout_views = data.heldout.size();
  report.heldout_pixels_per_view = options.final_eval_pixels;
  if (!psnrs.empty()) report.heldout_psnr = Mean(psnrs);
  if (!evaluation.training.empty()) report.training_psnr = Mean(evaluation.training);
  if (!evaluation.fitted.empty()) report.heldout_psnr_fitted = Mean(evaluation.fitted);
  report.heldout_step_scale = DefaultStepScale(trainer.model());  // Trainer::HeldoutPsnr's
  for (size_t v = 0; v < psnrs.size(); ++v) report.heldout_per_view.push_back({data.heldout[v].name, psnrs[v]});
  report.evaluations_during_training = {session.evaluations, session.evaluation_seconds, options.eval_pixels};
  report.throughput = session.steps;
  report.samples_per_ray_rendered = eval_stats.rays > 0 ? double(eval_stats.samples_evaluated) / eval_stats.rays : 0;
  report.render_seconds_per_view = psnrs.empty() ? 0.0 : eval_stats.seconds / psnrs.size();
  const NerfModel& model = trainer.model();
  report.occupied_fraction = model.occupancy.OccupiedFraction();
  report.field = model.field->Config();
  report.trainer = {trainer_options.march_step,
                    model.march_step,
                    trainer_options.learning_rate,
                    trainer_options.distortion_weight,
                    trainer_options.batch_samples,
                    trainer_options.late_batch_samples,
                    SceneSpaceName(trainer_options.space),
                    trainer_options.appearance,
                    trainer_options.refine_cameras,
                    trainer_options.error_sampling,
                    trainer_options.random_background  ? BackgroundChoice::kRandom
                    : trainer_options.learn_background ? BackgroundChoice::kLearnt
                                                       : BackgroundChoice::kFixed,
                    {model.background[0], model.background[1], model.background[2]}};
  report.appearance = AppearanceReport(trainer, data);
  FieldFit fit{report.heldout_psnr,
               report.training_psnr,
               HeldoutViewFits(data, psnrs),
               trainer_options.learn_background,
               report.trainer.background_colour,
               evaluation.behind.MeanColour(),
               trainer_options.space == SceneSpace::kBounded,
               report.occupied_fraction,
               report.samples_per_ray_rendered};
  report.warnings = CheckFieldFit(fit);
  return report;
}

}  // namespace

namespace {

// What a finished training writes besides the model: train_report.json, metrics.csv and psnr.png; returns the
// report.
TrainReport WriteTrainReport(const TrainResult& out, Trainer& trainer, const TrainingSetup& setup,
                             const FinalEvaluation& evaluation, const RunState& state, int resumed_from,
                             const SessionLog& session, const BlockSteps& blocks) {
  TrainReport report =
      MakeTrainReport(trainer, setup.trainer, setup.options, setup.data, evaluation, resumed_from, session);
  report.steps += blocks.steps;
  report.wall_seconds = state.seconds + blocks.seconds;
  report.heldout_split = setup.heldout_split;
  report.heldout_rule = setup.heldout_rule;
  report.training_views_in_memory = setup.training_views_in_memory;
  report.heldout_views_in_memory = !setup.data.read_heldout;
  std::vector<std::string> names;
  for (const TrainView& view : setup.data.train) names.push_back(view.name);
  report.camera_refinement = CameraRefinementJson(names, trainer.camera_corrections());
  WriteJsonAtomic(out.report(), report.ToJson());
  const std::string metrics = "wall_seconds,step,train_loss,heldout_psnr\n" + state.metrics;
  WriteFileAtomic(out.metrics(), metrics);
  const PlotSeries curve = CsvSeries("held-out PSNR", metrics, 0, 3);
  if (!curve.x.empty()) {
    WriteOrExplain([&] {
      WriteLinePlot(out.psnr_plot(), {"held-out PSNR against training time", "training time (s)", "PSNR (dB)"},
                    {curve});
    });
  }
  return report;
}

}  // namespace

void TrainStage::RunPart(StageContext& context, const std::string& work, int part) const {
  if (work != kBlockWork) return Stage::RunPart(context, work, part);
  TrainBlockAlone(context, part - 1);
}

void TrainStage::Run(StageContext& context) const {
  TrainingSetup setup;
  LoadTrainingSetup(context, &setup);
  const TrainOptions& options = setup.options;
  const TrainingData& data = setup.data;
  Trainer trainer(setup.trainer, data);
  const double budget = ResolvedTimeBudget(options);
  LogInfo(format("train: {} field, {} scene, preset {}, {} training and {} held-out ({}) views, {}",
                 EnumName(options.field), SceneSpaceName(setup.trainer.space), EnumName(options.preset),
                 data.train.size(), data.heldout.size(), EnumName(setup.heldout_split),
                 budget > 0 ? format("{:.0f} s budget", budget) : format("{} steps", options.steps)));

  RunState state;
  const fs::path checkpoint = CheckpointFile(context);
  int resumed_from = 0;
  if (LoadRunCheckpoint(checkpoint, context.key, name(), &state,
                        [&](BinaryReader* reader) { trainer.LoadCheckpoint(reader); })) {
    resumed_from = trainer.step();
    LogInfo(format("train: resumed at step {} ({:.1f} s of training) from {}", trainer.step(), state.seconds,
                   checkpoint.string()));
  }
  SessionLog session;
  const bool blocks = options.blocks > 1;
  TrainUntilDone(trainer, data, options, blocks ? kWholePart : BudgetPart{}, checkpoint, context.key,
                 setup.window.get(), &state, &session);
  const BlockSteps block_steps = blocks ? TrainByBlocks(context, setup, state, &trainer) : BlockSteps{};

  if (!ModelIsFinite(trainer.model())) throw InternalError("training ended with non-finite parameters");
  FinalEvaluation evaluation;
  evaluation.heldout = trainer.HeldoutPsnr(options.final_eval_pixels, &evaluation.stats, CheckCancel,
                                           &evaluation.fitted, &evaluation.behind);
  evaluation.training = trainer.TrainingPsnr(options.final_eval_pixels, kTrainingViewsScored, CheckCancel);
  const std::vector<double>& psnrs = evaluation.heldout;
  NerfModel& model = trainer.model();
  model.info = {{"transforms", setup.transforms.string()},
                {"steps", trainer.step() + block_steps.steps},
                {"heldout_psnr", Mean(psnrs)},
                {"distortion_weight", setup.trainer.distortion_weight},
                {"depth_weight", setup.trainer.depth_weight},
                {"appearance", setup.trainer.appearance},
                {"refine_cameras", setup.trainer.refine_cameras}};
  const TrainResult out{context.output_dir};
  WriteOrExplain([&] { SaveModel(model, out.model()); });
  if (setup.window) setup.training_views_in_memory = setup.window->size();
  const TrainReport report =
      WriteTrainReport(out, trainer, setup, evaluation, state, resumed_from, session, block_steps);
  context.summary = {{"steps", report.steps},
                     {"train_seconds", report.wall_seconds},
                     {"heldout_psnr", report.heldout_psnr ? nlohmann::json(*report.heldout_psnr) : nullptr}};
  if (blocks) context.summary["train_blocks"] = options.blocks;
  LogInfo(format(
      "train: {} steps in {:.1f} s ({:.2f} M samples/s, {:.1f} a ray); held-out PSNR {:.2f} dB over {} views ({:.1f} "
      "samples per ray rendered)",
      report.steps, report.wall_seconds, session.steps.SamplesPerSecond() / 1e6, session.steps.SamplesPerRay(),
      Mean(psnrs), psnrs.size(), report.samples_per_ray_rendered));
  LogFitWarnings(TrainResult::kId.name, report.warnings);
}

}  // namespace p2n
