#pragma once
// The field trained by spatial blocks (train.blocks, for captures too large for one field in the time): the field is
// trained whole over the first part of the budget (kWholePart, stages/train_stage.cc); the field's cube is then cut
// into slabs holding equal shares of the surface the training views see, and each slab's field trained on from the
// whole one over the rest of the budget, on the views that see it, as parts of the stage's work (kBlockWork,
// StageContext::RunParts: in turn here, or as jobs of a scheduler at once). The composite (nerf/blocked_field.h)
// answers each point from its slab's field. The start of the blocks and each block's result are kept in the stage's
// resume folder until the stage completes, so that a resumed run goes on with the blocks left.

#include "nerf/trainer.h"
#include "pipeline/stage.h"
#include "stages/train_run.h"

namespace p2n {

// The schedule's part the whole field trains over, and the part each block goes on over.
inline constexpr SchedulePart kWholePart{0, 0.5};
inline constexpr SchedulePart kBlockPart{0.5, 1};

// The blocks' optimisation steps and seconds, summed.
struct BlockSteps {
  int steps = 0;
  double seconds = 0;
};

// After the whole part (`whole`, at `state`): its end kept as the stage's checkpoint, the blocks trained from it, and
// their composite adopted by `whole` (Trainer::AdoptModel) for the evaluation and the report. The photos of `setup`
// in memory are lent to each block while it trains, and are back when this returns; those of its window over the
// photos are let go while the blocks train and read back after, so that the stage holds train.photo_memory's worth
// once.
BlockSteps TrainByBlocks(const StageContext& context, TrainingSetup& setup, const RunState& state, Trainer* whole);

// Block `b`'s part alone (in a job of its own), from the whole part's checkpoint.
void TrainBlockAlone(const StageContext& context, int b);

}  // namespace p2n
