#pragma once
// A stage's work by spatial blocks (train.blocks, splat.blocks), the same for the field and the splats: optimised
// whole over the first part of the budget (kWholePart), its end kept as the stage's checkpoint; then cut into slabs
// (base/slabs.h), and each slab's block optimised on from the whole over the rest (kBlockPart), on the training
// views that see it, as parts of the stage's work (kBlockWork, StageContext::RunParts: in turn here, or as jobs of a
// scheduler at once); the blocks' results merged. Where the blocks begin (blocks.json), each block's checkpoint and a
// record of each finished block stay in the stage's resume folder until the stage completes, so that a resumed run
// goes on with the blocks left and a block's job starts where the others do. Each stage brings its own step (how a
// block is optimised and merged); this file is the rest.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/posed_image.h"
#include "pipeline/stage.h"
#include "stages/fitting/timed_run.h"

namespace p2n {

// The share of the budget optimised whole, and the rest each block goes on over: the other blocks, drawn as the whole
// left them, must already look like the scene (docs/benchmarks.md, splats by blocks).
inline constexpr BudgetPart kWholePart{0, 0.5};
inline constexpr BudgetPart kBlockPart{0.5, 1};

// Block b's checkpoint in the resume folder.
std::filesystem::path BlockCheckpoint(const StageContext& context, int b);

// Keeps where the blocks begin: `start` (what the stage needs to cut them again, or the cut itself) with the result's
// key and the names of the training views (`train`) the blocks index.
void SaveBlocksStart(const StageContext& context, nlohmann::json start, const std::vector<TrainView>& train);
// What SaveBlocksStart kept, when this run kept it.
std::optional<nlohmann::json> LoadBlocksStart(const StageContext& context);
// The same for block b's job (`stage`: the stage's name, for messages): ExternalToolError when it is missing or not
// this run's, UserError when `train` are not the views it names (CheckSameViews; `transforms`: the poses stage's file).
nlohmann::json BlocksStartOfJob(const StageContext& context, const std::string& stage, int b,
                                const std::vector<TrainView>& train, const std::filesystem::path& transforms);

// The whole part's end, from the stage's checkpoint, for block b's job: `load` reads the optimiser; ExternalToolError
// when it is missing or not this run's.
void LoadWholePart(const StageContext& context, const std::string& stage, int b, RunState* state,
                   const std::function<void(BinaryReader*)>& load);

// UserError unless 0 <= b < count.
void CheckBlockIndex(const std::string& stage, int b, int count);

// Runs `run_block(b)` for each of blocks 0..count - 1 that has not finished (MarkBlockDone) in this run, as parts of
// the stage's work; returns those it ran.
std::vector<int> RunPendingBlocks(const StageContext& context, int count, const std::function<void(int b)>& run_block);
// Records that block b has finished, with `record` (what the stage needs of it after).
void MarkBlockDone(const StageContext& context, int b, nlohmann::json record);
// What MarkBlockDone recorded of block b; ExternalToolError when it did not finish.
nlohmann::json FinishedBlock(const StageContext& context, const std::string& stage, int b);

}  // namespace p2n
