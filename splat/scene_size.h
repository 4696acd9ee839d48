#pragma once
// How large a scene is against what one photo sees: an orbit's or a forward-facing capture's views each see most of
// it, a street's or a drone survey's a small part, and a large scene takes more splats (each view still drawing about
// as many; stages/fitting/splat_stage.h, PlacedSplats).

#include <cstddef>
#include <vector>

#include "base/posed_image.h"
#include "splat/gaussians.h"

namespace p2n {

// Whether `position` projects into `camera`'s picture, in front of it beyond `near`.
bool InPicture(const PinholeCamera& camera, const float* position, double near);

// The mean over `views` of the share of `splats` whose mean is in the view's picture (InPicture); 1 without splats.
// Up to kShareViews views spread evenly and kShareSplats splats (every k-th) are counted: well under a second.
double MeanViewShare(const std::vector<TrainView>& views, const Gaussians<float>& splats, double near);
inline constexpr size_t kShareViews = 64, kShareSplats = 20'000;

}  // namespace p2n
