#pragma once
// Optimising splats by spatial blocks, for captures too large for one optimisation in the time: the splats cut into
// slabs of equal count along the axis where they spread most; each slab optimised by its own trainer on the training
// views that see it, with every other splat drawn as it was when the blocks began (so that the pixels showing other
// slabs are explained by them); the results merged, each splat owned by the slab it began in (its children from
// densification too) wherever the optimisation moved it, so that none is lost or doubled at a cut. The other slabs
// must already look like the scene when the blocks begin: the splat stage optimises the whole first
// (stages/splat_optimisation.h).

#include <cstddef>
#include <vector>

#include "base/posed_image.h"
#include "splat/gaussians.h"

namespace p2n {

struct SplatBlocks {
  int axis = 0;
  std::vector<float> cuts;  // ascending; block b holds the means in [cuts[b - 1], cuts[b]) along `axis`

  int count() const { return static_cast<int>(cuts.size()) + 1; }
  int BlockOf(const float* position) const;
};

// `count` slabs of (nearly) equal numbers of `splats`, across the axis where their means spread most (between the
// 5th and 95th percentiles, so that a few far splats do not choose it).
SplatBlocks CutIntoBlocks(const Gaussians<float>& splats, int count);

// Whether each of `splats` is in `block`.
std::vector<bool> InBlock(const Gaussians<float>& splats, const SplatBlocks& blocks, int block);
// The splats in `block` (inside), or in every other block (!inside), in order.
Gaussians<float> SplatsOfBlock(const Gaussians<float>& splats, const SplatBlocks& blocks, int block, bool inside);

// The indices (ascending) of the views that see `block`: those where at least `min_share` of the splats whose mean
// projects into the picture, in front of the camera beyond `near`, are the block's.
std::vector<size_t> ViewsOfBlock(const std::vector<TrainView>& views, const Gaussians<float>& splats,
                                 const SplatBlocks& blocks, int block, double min_share, double near);

// One set of splats from the blocks' results (`optimised[b]`: block b's splats after its optimisation), each block's
// kept whole.
Gaussians<float> MergeBlocks(const std::vector<Gaussians<float>>& optimised);

}  // namespace p2n
