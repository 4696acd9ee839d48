#pragma once
// What a training run of the train stage is made of (stages/fitting/train_stage.cc, and its blocks:
// stages/fitting/train_blocks.h): the options resolved and the photos loaded (or a window over them), and the timed,
// resumable loop that trains a field until its share of the budget is spent.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "base/decoded_photos.h"
#include "base/photo_window.h"
#include "nerf/trainer.h"
#include "pipeline/stage.h"
#include "stages/fitting/timed_run.h"
#include "stages/fitting/train_options.h"
#include "stages/stage_reports.h"

namespace p2n {

// What a training is made from: the stage's options, the trainer's they resolve to, and the data.
struct TrainingSetup {
  TrainOptions options;
  TrainerOptions trainer;
  TrainingData data;
  std::filesystem::path transforms;  // the poses stage's transforms.json
  ViewSplit heldout_split = ViewSplit::kVal;
  std::string heldout_rule;
  // Training view v's pixels, from the decoded copy where there is one, else from its file.
  PhotoWindow::Loader read_photo;
  // Where the training photos are too many for memory: their decoded copy, and a window over them.
  std::shared_ptr<const DecodedPhotos> photos;
  std::unique_ptr<PhotoWindow> window;
  std::optional<size_t> training_views_in_memory;  // with a window over the training photos
};

// Which photos LoadTrainingSetup loads: every training and held-out photo (or a window over the training photos, and
// the held-out ones read at each evaluation), or none (a field block's job reads its own views' photos by
// TrainingSetup::read_photo).
enum class SetupPhotos { kAll, kNone };

// The stage's options, the poses stage's views and photos (or a window over the photos where they would take more than
// train.photo_memory, decoded into the stage's resume folder; the held-out photos in what they leave of it, else
// through a decoded copy: LoadHeldoutPhotos) and the trainer's options, into `setup` (in place: the window points into
// its data).
void LoadTrainingSetup(const StageContext& context, TrainingSetup* setup, SetupPhotos photos = SetupPhotos::kAll);

// This session of the run (a resumed run counts from its resumption): its held-out evaluations during training and
// its steps.
struct SessionLog {
  int evaluations = 0;
  double evaluation_seconds = 0;
  TrainReport::Throughput steps;
};

// Trains until `part`'s share of the budget (train.time_budget's seconds, else train.steps) is spent, from where
// `state` left off: a metrics row at every evaluation (evaluations take at most train.eval_share of the wall time),
// checkpoints every train.checkpoint_interval seconds into `checkpoint`, tagged with the result's `key`. With a
// `window` over the training photos, each step trains on those it holds at that step.
void TrainUntilDone(Trainer& trainer, const TrainingData& data, const TrainOptions& options, BudgetPart part,
                    const std::filesystem::path& checkpoint, const std::string& key, PhotoWindow* window,
                    RunState* state, SessionLog* session);

// train.photo_memory in bytes.
double PhotoMemoryBytes(const TrainOptions& options);

// Whether every parameter of the model's field is finite.
bool ModelIsFinite(NerfModel& model);

// Stops an evaluation on Ctrl-C (its progress callback).
void CheckCancel(size_t);

}  // namespace p2n
