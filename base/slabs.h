#pragma once
// Slabs of a scene along one axis: how the stages that work by spatial blocks (a field's train.blocks, the splats'
// splat.blocks) cut the scene, and which training views each slab is trained on. The points cut are what the photos
// see (the field's surface, the splats' means); the cut gives each slab an equal share of them, across the axis where
// they spread most.

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace p2n {

// Slab b holds the points whose coordinate on `axis` lies in [cuts[b - 1], cuts[b]) (the first from -infinity, the
// last to +infinity).
struct Slabs {
  int axis = 0;
  std::vector<double> cuts;  // ascending

  int count() const { return static_cast<int>(cuts.size()) + 1; }
  int SlabOf(double coordinate) const;
};

// The most slabs a cut makes (a model file holds a whole field for each).
inline constexpr int kMaxSlabs = 256;

// `count` slabs holding (nearly) equal numbers of `points` (3 x n), across the axis where they spread most between
// their 5th and 95th percentiles (so that a few far points do not choose it); fewer where quantiles coincide (one cut
// each); one without points. std::invalid_argument for a count outside 1..kMaxSlabs.
Slabs CutIntoSlabs(const Eigen::Matrix3Xd& points, int count);

// A view sees a slab when at least this share of the points it sees (and at least one) are the slab's.
inline constexpr double kSlabViewShare = 0.1;

// Whether a view that sees the points `seen` (3 x n) sees `slab`: at least one of them, and at least `min_share` of
// them, are in it.
bool SeesSlab(const Eigen::Matrix3Xd& seen, const Slabs& slabs, int slab, double min_share = kSlabViewShare);

// The views (indices, ascending) that see `slab` (SeesSlab), `seen[v]` being what view v sees.
std::vector<size_t> ViewsOfSlab(const std::vector<Eigen::Matrix3Xd>& seen, const Slabs& slabs, int slab,
                                double min_share = kSlabViewShare);

}  // namespace p2n
