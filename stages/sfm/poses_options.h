#pragma once
// The poses stage's options (poses.*), apart from the stage so that the import stage, which writes the same result,
// includes them alone.

#include "pipeline/options.h"

namespace p2n {

// Training images are at most this many pixels on their longest side by default: the largest photos whose figures
// were measured in the default time (fox's 1080 x 1920). A 12-megapixel phone photo would have 6 times fox's pixels
// for the same minutes of training and splat steps 6 times as slow; it becomes 1920 x 1440.
inline constexpr int kDefaultMaxTrainingImageSize = 1920;

struct PosesOptions {
  static constexpr const char* kSection = "poses";  // its options are poses.NAME

  int holdout_every = 8;  // every Nth view (in name order) is held out for evaluation (AssignHoldout); 0: none
  bool normalize = true;  // centre, rotate (up = +z) and scale the scene into the unit cube
  int max_image_size = kDefaultMaxTrainingImageSize;  // longest side of the images later stages read; 0: as they are
  int train_views = 0;                                // training views kept (KeepTrainingViews); 0: all
  bool masks = true;                                  // a masks/ folder beside the photos gives their alpha

  template <class V>
  void Visit(V& v) {
    v("holdout_every", holdout_every,
      "every Nth view is held out for evaluation (with fewer than 20, as many inside the span of the others); 0: none",
      "views");
    v("normalize", normalize, "centre, turn upright and scale the scene into the unit cube");
    v("max_image_size", max_image_size,
      "longest side of the images that training, splats, renders and evaluations use (larger ones are downsized "
      "with an area filter, their intrinsics scaled; the cameras are solved on the photos as they are); 0: as they "
      "are",
      "px");
    v("train_views", train_views,
      "keep this many of the training views, spread evenly in name order, and leave the others out of training "
      "(split \"unused\"): to measure what a capture of fewer photos would give, on the same held-out views; 0: all",
      "views");
    v("masks", masks,
      "use the masks/ folder in the photo folder or dataset (one mask a photo, white on the subject, named as the "
      "photo) as the photos' alpha, so that the scene is the subject alone");
  }
  void Check() const;
};

}  // namespace p2n
