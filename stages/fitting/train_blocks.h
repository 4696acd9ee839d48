#pragma once
// The field's step of a run by blocks (stages/fitting/blocked_run.h, train.blocks: captures too large for one field in
// the time): the field's cube cut into slabs holding equal shares of the surface the training views see, each slab's
// field trained on from the whole one on the views that see it, and the composite (nerf/blocked_field.h) answering
// each point from its slab's field.

#include "nerf/trainer.h"
#include "pipeline/stage.h"
#include "stages/fitting/blocked_run.h"
#include "stages/fitting/train_run.h"

namespace p2n {

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
