#pragma once
// Optimising splats by spatial blocks, for captures too large for one optimisation in the time: the splats cut into
// slabs of equal count along the axis where their means spread most (base/slabs.h, the cut a field's blocks make
// too); each slab optimised by its own trainer on the training views that see it, with every other splat drawn as it
// was when the blocks began (so that the pixels showing other slabs are explained by them); the results merged, each
// splat owned by the slab it began in (its children from densification too) wherever the optimisation moved it, so
// that none is lost or doubled at a cut. The other slabs must already look like the scene when the blocks begin: the
// splat stage optimises the whole first (stages/fitting/splat_optimisation.h).

#include <cstddef>
#include <vector>

#include "base/posed_image.h"
#include "base/slabs.h"
#include "splat/gaussians.h"

namespace p2n {

// The splats' means, one column each.
Eigen::Matrix3Xd Means(const Gaussians<float>& splats);

// Whether each of `splats` is in `slab`.
std::vector<bool> InSlab(const Gaussians<float>& splats, const Slabs& slabs, int slab);
// The splats in `slab` (inside), or in every other slab (!inside), in order.
Gaussians<float> SplatsOfSlab(const Gaussians<float>& splats, const Slabs& slabs, int slab, bool inside);

// The indices (ascending) of the views that see `slab` (SeesSlab): the points they see are the means of `splats`
// that project into their picture, in front of the camera beyond `near`.
std::vector<size_t> ViewsOfSlab(const std::vector<TrainView>& views, const Gaussians<float>& splats, const Slabs& slabs,
                                int slab, double near);

// One set of splats from the slabs' results (`optimised[b]`: slab b's splats after its optimisation), each kept whole.
Gaussians<float> MergeSlabs(const std::vector<Gaussians<float>>& optimised);

}  // namespace p2n
