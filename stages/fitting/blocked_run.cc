#include "stages/fitting/blocked_run.h"

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "stages/stage_io.h"
#include "stages/stage_results.h"
#include "stages/training_data.h"

namespace p2n {

namespace fs = std::filesystem;

namespace {

fs::path BlocksStartFile(const StageContext& context) { return context.resume_dir / "blocks.json"; }
fs::path BlockDoneFile(const StageContext& context, int b) {
  return context.resume_dir / format("block{}.json", b + 1);
}

}  // namespace

fs::path BlockCheckpoint(const StageContext& context, int b) {
  return context.resume_dir / format("checkpoint_block{}.bin", b + 1);
}

void SaveBlocksStart(const StageContext& context, nlohmann::json start, const std::vector<TrainView>& train) {
  start["key"] = context.key;
  start["names"] = ViewNames(train);
  WriteOrExplain([&] { WriteJsonAtomic(BlocksStartFile(context), start); });
}

std::optional<nlohmann::json> LoadBlocksStart(const StageContext& context) {
  return OfThisRun(context, BlocksStartFile(context));
}

nlohmann::json BlocksStartOfJob(const StageContext& context, const std::string& stage, int b,
                                const std::vector<TrainView>& train, const fs::path& transforms) {
  const std::optional<nlohmann::json> start = LoadBlocksStart(context);
  if (!start) {
    throw ExternalToolError(
        format("{}: block {}: where the blocks begin ({}) is missing or not this run's; run the "
               "stage again",
               stage, b + 1, BlocksStartFile(context).string()));
  }
  CheckSameViews(start->value("names", std::vector<std::string>{}), train, format("{}: block {}", stage, b + 1),
                 transforms);
  return *start;
}

void LoadWholePart(const StageContext& context, const std::string& stage, int b, RunState* state,
                   const std::function<void(BinaryReader*)>& load) {
  if (!LoadRunCheckpoint(CheckpointFile(context), context.key, stage, state, load)) {
    throw ExternalToolError(
        format("{}: block {}: the whole part's result {} is missing or not this run's; run the "
               "stage again",
               stage, b + 1, CheckpointFile(context).string()));
  }
}

void CheckBlockIndex(const std::string& stage, int b, int count) {
  if (b < 0 || b >= count) throw UserError(format("{}: there is no block {} of {}", stage, b + 1, count));
}

std::vector<int> RunPendingBlocks(const StageContext& context, int count, const std::function<void(int b)>& run_block) {
  std::vector<int> pending;  // block b is part b + 1
  for (int b = 0; b < count; ++b) {
    if (!OfThisRun(context, BlockDoneFile(context, b))) pending.push_back(b + 1);
  }
  context.RunParts(kBlockWork, pending, [&](int part) { run_block(part - 1); });
  std::vector<int> ran;
  for (const int part : pending) ran.push_back(part - 1);
  return ran;
}

void MarkBlockDone(const StageContext& context, int b, nlohmann::json record) {
  record["key"] = context.key;
  WriteOrExplain([&] { WriteJsonAtomic(BlockDoneFile(context, b), record); });
}

nlohmann::json FinishedBlock(const StageContext& context, const std::string& stage, int b) {
  const std::optional<nlohmann::json> done = OfThisRun(context, BlockDoneFile(context, b));
  if (!done) {
    throw ExternalToolError(format("{}: block {} did not finish ({} is missing); run the stage again", stage, b + 1,
                                   BlockDoneFile(context, b).string()));
  }
  return *done;
}

}  // namespace p2n
