#pragma once
// What training a field by spatial blocks (train.blocks) is made of, apart from the stage that runs it: where the
// views see the scene's surface (what base/slabs.h cuts), a block's field started from
// the whole one, and the blocks' models made one (nerf/blocked_field.h).

#include <vector>

#include "base/posed_image.h"
#include "nerf/blocked_field.h"
#include "nerf/nerf_model.h"

namespace p2n {

// Where `model` shows each view's surface: the points (the field's unit cube) at which a grid of `rays_per_side` x
// `rays_per_side` of its rays end (their median depth, where the opacity reaches a half); one matrix a view.
std::vector<Eigen::Matrix3Xd> SurfaceSeen(const NerfModel& model, const std::vector<TrainView>& views,
                                          int rays_per_side);

// Copies the parameters of `from` (dense and the trainable encoding's) into `to`, a field of the same config;
// std::invalid_argument when the configs differ.
void CopyFieldParameters(RadianceField<float>& from, RadianceField<float>* to);

// One model of the blocks' (blocks[b] trained for slab b; the same scene space and occupancy resolution): the
// composite field, each occupancy cell from the grid of the slab its centre lies in, the finest of their march steps
// (a block may end before the trainer's switch to the fine step) and the mean of their backgrounds; the first
// block's info. std::invalid_argument when they do not match.
NerfModel MergeBlockModels(const Slabs& slabs, std::vector<NerfModel> blocks);

}  // namespace p2n
