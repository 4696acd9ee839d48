#include "stages/fitting/train_run.h"

#include <algorithm>
#include <cmath>

#include "base/errors.h"
#include "base/float_image.h"
#include "base/format.h"
#include "formats/dataset_import.h"
#include "pipeline/cancel.h"
#include "pipeline/log.h"
#include "stages/fitting/train_settings.h"
#include "stages/photo_memory.h"
#include "stages/stage_io.h"
#include "stages/training_data.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

constexpr int kMaxConsecutiveSkips = 50;

// A window over the training photos when LoadTrainingData left their pixels out (they would take more than
// train.photo_memory), reading them from a file in `folder` they are decoded into first (by `decode`); none when they
// are in memory.
void MakePhotoWindow(const PhotoWindow::Loader& decode, const fs::path& folder, TrainingSetup* setup) {
  const TrainOptions& options = setup->options;
  TrainingData* data = &setup->data;
  if (!data->train.front().pixels.empty()) return;
  const std::string option = OptionKey(options, options.photo_memory);
  setup->photos = DecodeForWindow(data->train, options.photo_memory, option, "train", folder, decode).photos;
  setup->read_photo = [photos = setup->photos](size_t v) { return photos->Read(v); };
  setup->window = std::make_unique<PhotoWindow>(&data->train, setup->read_photo, PhotoMemoryBytes(options),
                                                static_cast<uint64_t>(options.seed));
}

}  // namespace

void LoadTrainingSetup(const StageContext& context, TrainingSetup* setup, SetupPhotos photos) {
  setup->options = ReadOptions<TrainOptions>(context.config);
  const TrainOptions& options = setup->options;
  setup->transforms = Upstream<PosesResult>(context).transforms();
  const auto dataset =
      std::make_shared<const ImportedDataset>(LoadTransformsJson(setup->transforms, context.workspace.root()));
  const ImportedDataset& poses = *dataset;
  setup->heldout_split = HeldoutSplit(poses);
  setup->heldout_rule = poses.meta.heldout_rule;
  const std::vector<const ImportedView*> train = TrainingViews(poses);
  const double depth_weight = DepthWeight(options, train.size());
  const PhotoWindow::Loader decode = [dataset, train](size_t v) { return LoadTrainView(*train[v]).pixels; };
  setup->read_photo = decode;
  if (photos == SetupPhotos::kAll) {
    setup->data = LoadTrainingData(poses, depth_weight > 0, PhotoMemoryBytes(options));
    MakePhotoWindow(decode, context.resume_dir, setup);
    LoadHeldoutPhotos(poses, options.photo_memory, OptionKey(options, options.photo_memory), "train",
                      context.resume_dir, &setup->data);
  } else {
    setup->data = LoadTrainingCameras(poses, depth_weight > 0);
  }
  setup->trainer = MakeTrainerOptions(options, ResolveSceneSpace(options, poses));
  setup->trainer.depth_weight = depth_weight;
  const TrainView* with_alpha = FirstWithAlpha(setup->data.train);
  const bool alpha = with_alpha != nullptr;
  const BackgroundChoice background = options.background;
  if (background == BackgroundChoice::kLearnt && alpha) {
    throw UserError(
        format("{} is learnt, but {} (in {}) has alpha: it was composited on a known colour, which must stay; use "
               "auto or fixed",
               OptionKey(options, options.background), with_alpha->name, setup->transforms.string()));
  }
  const bool learn_when_auto = !alpha && !setup->data.background_known;
  const bool automatic = background == BackgroundChoice::kAuto;
  setup->trainer.random_background = background == BackgroundChoice::kRandom || (automatic && alpha);
  setup->trainer.learn_background = background == BackgroundChoice::kLearnt || (automatic && learn_when_auto);
}

double PhotoMemoryBytes(const TrainOptions& options) { return MegabytesToBytes(options.photo_memory); }

void CheckCancel(size_t) { ThrowIfCancelled(); }

bool ModelIsFinite(NerfModel& model) {
  const auto finite = [](const float* values, size_t count) {
    return std::all_of(values, values + count, [](float v) { return std::isfinite(v); });
  };
  for (const ParamBlock<float>& block : model.field->DenseParams()) {
    if (!finite(block.data, block.size)) return false;
  }
  Encoding<float>* grid = model.field->TrainableEncoding();
  return grid == nullptr || finite(grid->params(), grid->num_params());
}

void TrainUntilDone(Trainer& trainer, const TrainingData& data, const TrainOptions& options, BudgetPart part,
                    const fs::path& checkpoint, const std::string& key, PhotoWindow* window, RunState* state,
                    SessionLog* session) {
  const double budget = ResolvedTimeBudget(options) * part.share();
  const int steps = options.steps > 0 ? std::max(1, static_cast<int>(std::lround(options.steps * part.share()))) : 0;
  const RunLoop loop{TrainResult::kId.name,      budget, steps, options.eval_interval, options.eval_share, true,
                     options.checkpoint_interval};
  int consecutive_skips = 0;
  const auto step = [&](double share) -> std::optional<double> {
    if (window != nullptr && window->MoveTo(trainer.step())) trainer.SampleFrom(window->resident());
    const StepResult result = trainer.Step(part.from + share * part.share());
    session->steps.rays += result.rays;
    session->steps.samples += result.samples;
    if (!result.skipped) {
      consecutive_skips = 0;
      return result.loss;
    }
    LogWarning(format("train: step {} skipped: {}", trainer.step(), result.problem));
    if (++consecutive_skips >= kMaxConsecutiveSkips) {
      throw InternalError(
          format("training failed: {} steps in a row were not finite (last: {})", consecutive_skips, result.problem));
    }
    return std::nullopt;
  };
  const auto add_row = [&](RunState* run) {
    const double psnr =
        data.heldout.empty() ? std::nan("") : Mean(trainer.HeldoutPsnr(options.eval_pixels, nullptr, CheckCancel));
    const double loss = run->TakeMeanLoss(std::nan(""));
    run->metrics += format("{:.3f},{},{:.6g},{:.4f}\n", run->seconds, trainer.step(), loss, psnr);
  };
  const auto save = [&](const RunState& run) {
    if (!ModelIsFinite(trainer.model())) return;
    WriteOrExplain([&] {
      SaveRunCheckpoint(checkpoint, key, run, [&](BinaryWriter* writer) { trainer.SaveCheckpoint(writer); });
    });
  };
  const RunSession run = loop.Run(
      state, [&] { return trainer.step(); }, step, add_row, save);
  session->steps.steps += run.steps;
  session->steps.seconds += run.step_seconds;
  session->evaluations += run.rows;
  session->evaluation_seconds += run.row_seconds;
}

}  // namespace p2n
