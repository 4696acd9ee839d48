#pragma once
// The schedule a splat optimisation steps through around its trainer (splat/splat_trainer.h), behind one call a step,
// as the field's trainer takes its own: coarse to fine (the photos at half size for a first part of the run) and a
// window over photos too many for memory (base/photo_window.h), the half-size copies following the window.

#include <cstddef>
#include <optional>
#include <vector>

#include "base/photo_window.h"
#include "base/posed_image.h"
#include "splat/splat_trainer.h"

namespace p2n {

// Whether the step after `steps` steps, at `progress` (the share of the run spent), is in the coarse part: on the
// photos at half size until `coarse_share` (splat.coarse) of the run is spent or 40 passes over the `train_views`
// training views are made, whichever comes first (docs/benchmarks.md, splats).
bool InCoarsePart(double coarse_share, double progress, int steps, size_t train_views);

class SplatSchedule {
 public:
  // Steps `trainer` on `views` (their pixels, or those `window` holds; null: every one in memory); `coarse_share` as
  // InCoarsePart's (0: no coarse part), whose passes count `train_views` views (the whole capture's, for a block too).
  SplatSchedule(SplatTrainer* trainer, const std::vector<TrainView>* views, PhotoWindow* window, double coarse_share,
                size_t train_views);

  // One step at `progress` (0..1 of the whole run): the trainer on the views at the size the part asks, the window
  // moved on; its loss, or nothing when the step was skipped.
  std::optional<double> Step(double progress);

 private:
  // The half-size views of the photos the window holds: those it took in halved, those it let go dropped.
  void FollowWindow();

  SplatTrainer* trainer_;
  const std::vector<TrainView>* views_;
  PhotoWindow* window_;
  double coarse_share_;
  size_t train_views_;
  std::vector<TrainView> coarse_;  // empty once the coarse part is over (or without one)
};

}  // namespace p2n
