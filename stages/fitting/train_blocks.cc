#include "stages/fitting/train_blocks.h"

#include <optional>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "nerf/camera_refinement.h"
#include "nerf/field_blocks.h"
#include "pipeline/log.h"
#include "stages/fitting/blocked_run.h"
#include "stages/photo_memory.h"
#include "stages/stage_io.h"
#include "stages/training_data.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

// Each view's surface is found by a grid of this many rays a side.
constexpr int kSurfaceRaysPerSide = 32;

// Where the blocks begin: the slabs, and the training views (indices) each slab's field trains on.
struct SlabsStart {
  Slabs slabs;
  std::vector<std::vector<size_t>> views;
};

fs::path SlabModelFile(const StageContext& context, int b) {
  return context.resume_dir / format("block{}_model.bin", b + 1);
}

// The training views with their cameras as the whole part left them (corrected where it refined them), without
// their pixels: what the surface is looked for from.
std::vector<TrainView> CorrectedCameras(const TrainingData& data, const Trainer& whole) {
  const std::vector<float>& corrections = whole.camera_corrections();
  std::vector<TrainView> views(data.train.size());
  for (size_t v = 0; v < views.size(); ++v) {
    const TrainView& view = data.train[v];
    views[v].camera = corrections.empty() ? view.camera : CorrectedCamera(view.camera, &corrections[v * kPoseParams]);
    views[v].near = view.near;
    views[v].far = view.far;
  }
  return views;
}

SlabsStart CutBlocks(const TrainingSetup& setup, const Trainer& whole) {
  const std::vector<Eigen::Matrix3Xd> seen =
      SurfaceSeen(whole.model(), CorrectedCameras(setup.data, whole), kSurfaceRaysPerSide);
  Eigen::Index total = 0;
  for (const Eigen::Matrix3Xd& points : seen) total += points.cols();
  Eigen::Matrix3Xd all(3, total);
  Eigen::Index at = 0;
  for (const Eigen::Matrix3Xd& points : seen) {
    all.middleCols(at, points.cols()) = points;
    at += points.cols();
  }
  SlabsStart start;
  start.slabs = CutIntoSlabs(all, setup.options.blocks);
  for (int b = 0; b < start.slabs.count(); ++b) start.views.push_back(ViewsOfSlab(seen, start.slabs, b));
  return start;
}

nlohmann::json SlabsStartJson(const SlabsStart& start) {
  return {{"axis", start.slabs.axis}, {"cuts", start.slabs.cuts}, {"views", start.views}};
}

SlabsStart SlabsStartOf(const nlohmann::json& json) {
  SlabsStart start;
  start.slabs.axis = json.at("axis").get<int>();
  start.slabs.cuts = json.at("cuts").get<std::vector<double>>();
  start.views = json.at("views").get<std::vector<std::vector<size_t>>>();
  return start;
}

// A block's training data: the training views that see it (`indices` of the setup's), their cameras as the whole
// part left them, and their pixels borrowed or read, or a window over them (BorrowViews); no held-out views (the
// composite is scored at the end).
struct BlockData {
  TrainingData data;
  BorrowedViews borrowed;  // into data.train, which outlives it
};

void LoadBlockData(TrainingSetup& setup, const Trainer& whole, const std::vector<size_t>& indices,
                   const fs::path& folder, BlockData* block) {
  const PhotoSource source{setup.read_photo,
                           setup.photos,
                           PhotoMemoryBytes(setup.options),
                           static_cast<uint64_t>(setup.options.seed),
                           folder,
                           "train: decoding the block's photos"};
  BorrowViews(&setup.data.train, indices, source, &block->data.train, &block->borrowed);
  const std::vector<TrainView> cameras = CorrectedCameras(setup.data, whole);
  for (size_t i = 0; i < indices.size(); ++i) block->data.train[i].camera = cameras[indices[i]].camera;
  block->data.background = setup.data.background;
  block->data.background_known = setup.data.background_known;
}

// The whole part's photos in its window (where the training photos take more than train.photo_memory), let go while
// the blocks train, each of which holds its own within the setting: the views they were.
std::vector<size_t> LetWindowGo(TrainingSetup& setup) {
  std::vector<size_t> held;
  if (!setup.window) return held;
  for (const size_t v : setup.window->resident()) {
    if (setup.data.train[v].pixels.empty()) continue;
    std::vector<uint8_t>().swap(setup.data.train[v].pixels);
    held.push_back(v);
  }
  return held;
}

// Reads back the photos LetWindowGo let go: the final evaluation scores the composite on the window's photos.
void ReadWindowBack(TrainingSetup& setup, const std::vector<size_t>& held) {
  for (const size_t v : held) setup.data.train[v].pixels = setup.photos->Read(v);
}

// Block b's part: its field trained on from the whole one, on the views that see it, for the rest of the budget
// (resuming from its own checkpoint); its model kept in the resume folder (the whole one where no view sees it).
void TrainBlock(const StageContext& context, TrainingSetup& setup, Trainer& whole, const SlabsStart& start, int b) {
  const std::vector<size_t>& views = start.views.at(b);
  LogInfo(format("train: block {} of {}: {} training views", b + 1, start.slabs.count(), views.size()));
  RunState state;
  int steps = 0;
  if (views.empty()) {
    SaveModel(whole.model(), SlabModelFile(context, b));
  } else {
    BlockData block;
    LoadBlockData(setup, whole, views, context.resume_dir, &block);
    TrainerOptions options = setup.trainer;
    options.refine_cameras = false;  // the cameras stay as the whole part left them, the same for every block
    options.seed += static_cast<uint64_t>(b) + 1;
    Trainer trainer(options, block.data);
    CopyFieldParameters(*whole.model().field, trainer.model().field.get());
    trainer.model().occupancy = whole.model().occupancy;
    trainer.model().background = whole.model().background;
    const fs::path checkpoint = BlockCheckpoint(context, b);
    LoadRunCheckpoint(checkpoint, context.key, TrainResult::kId.name, &state,
                      [&](BinaryReader* reader) { trainer.LoadCheckpoint(reader); });
    SessionLog session;
    TrainUntilDone(trainer, block.data, setup.options, kBlockPart, checkpoint, context.key, block.borrowed.window.get(),
                   &state, &session);
    if (!ModelIsFinite(trainer.model()))
      throw InternalError(format("block {} ended with non-finite parameters", b + 1));
    SaveModel(trainer.model(), SlabModelFile(context, b));
    steps = trainer.step();
  }
  MarkBlockDone(context, b, {{"steps", steps}, {"seconds", state.seconds}});
}

}  // namespace

BlockSteps TrainByBlocks(const StageContext& context, TrainingSetup& setup, const RunState& state, Trainer* whole) {
  SaveRunCheckpoint(CheckpointFile(context), context.key, state,
                    [&](BinaryWriter* writer) { whole->SaveCheckpoint(writer); });
  const std::optional<nlohmann::json> kept = LoadBlocksStart(context);
  const SlabsStart start = kept ? SlabsStartOf(*kept) : CutBlocks(setup, *whole);
  if (!kept) SaveBlocksStart(context, SlabsStartJson(start), setup.data.train);
  LogInfo(
      format("train: {} blocks across the {} axis of the field's cube, each trained on from here for the rest of "
             "the budget",
             start.slabs.count(), "xyz"[start.slabs.axis]));
  const std::vector<size_t> held = LetWindowGo(setup);
  RunPendingBlocks(context, start.slabs.count(), [&](int b) { TrainBlock(context, setup, *whole, start, b); });
  ReadWindowBack(setup, held);

  BlockSteps total;
  std::vector<NerfModel> models;
  for (int b = 0; b < start.slabs.count(); ++b) {
    const nlohmann::json done = FinishedBlock(context, TrainResult::kId.name, b);
    total.steps += done.value("steps", 0);
    total.seconds += done.value("seconds", 0.0);
    models.push_back(LoadModel(SlabModelFile(context, b)));
  }
  whole->AdoptModel(MergeBlockModels(start.slabs, std::move(models)));
  return total;
}

void TrainBlockAlone(const StageContext& context, int b) {
  TrainingSetup setup;
  LoadTrainingSetup(context, &setup, SetupPhotos::kNone);
  const std::string stage = TrainResult::kId.name;
  const SlabsStart start = SlabsStartOf(BlocksStartOfJob(context, stage, b, setup.data.train, setup.transforms));
  CheckBlockIndex(stage, b, start.slabs.count());
  Trainer whole(setup.trainer, setup.data);
  RunState state;
  LoadWholePart(context, stage, b, &state, [&](BinaryReader* reader) { whole.LoadCheckpoint(reader); });
  TrainBlock(context, setup, whole, start, b);
}

}  // namespace p2n
