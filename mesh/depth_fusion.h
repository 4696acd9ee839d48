#pragma once
// The surface the views' depths agree on: a truncated signed distance fused from depth maps (the field's renders of
// the training views) over a mesh's lattice. A point within the truncation of the depth a view sees there takes the
// signed distance that view gives it, averaged over such views; a point more views see empty space through than see
// near their surface is outside (a floater a few views saw is carved away); a point only ever behind the surface is
// inside; a point no view sees is outside. Its zero crossing (ExtractFusedSurface, mesh/mesh.h) has holes where no
// view saw a surface, not fog shells.

#include <vector>

#include "base/camera.h"
#include "base/float_image.h"
#include "mesh/mesh.h"

namespace p2n {

struct DepthMap {
  PinholeCamera camera;
  const FloatImage* depth = nullptr;    // distance along each pixel's ray (its direction of unit length)
  const FloatImage* opacity = nullptr;  // below min_opacity the pixel sees empty space
};

struct FusionOptions {
  double truncation_cells = 3;  // the truncation, in the lattice's cells
  float min_opacity = 0.5f;
};

// The fused signed distance over the lattice of `lattice` (its cube and resolution), in units of the truncation
// (-1 inside .. 1 outside), negative inside; value (i * n + j) * n + k at LatticePoint(lattice, i, j, k).
std::vector<float> FuseDepths(const std::vector<DepthMap>& maps, const MeshOptions& lattice,
                              const FusionOptions& options);

}  // namespace p2n
