#pragma once
// The sfm stage's options (sfm.*), apart from the stage so that its helpers include them alone.

#include <string>

#include "pipeline/options.h"
#include "stages/sfm/matcher_choice.h"

namespace p2n {

struct SfmOptions {
  static constexpr const char* kSection = "sfm";  // its options are sfm.NAME

  std::string camera_model = "RADIAL";  // COLMAP camera model of the photos
  bool single_camera = true;            // one camera shared by the photos of one camera group (CameraGroups)
  Matcher matcher = Matcher::kAuto;     // auto: AutoMatcher (matcher_choice.h)
  int exhaustive_max_images = 100;      // photos above which auto matching is sequential or by retrieval
  int sequential_overlap = 12;          // neighbours each photo is matched with (sequential)
  int retrieval_neighbours = 20;        // most similar photos each photo is matched with (vocab_tree), and half more
  int hierarchical_min_images = 500;    // photos from which COLMAP's hierarchical mapper maps them; 0: never
  int leaf_max_images = 200;            // photos in one of its clusters at most
  int max_image_size = 1024;            // longest side for feature extraction, pixels
  int block_images = 100;               // photos a scheduler's job extracts or matches at most (runtime)
  int max_num_features = 2048;          // features per photo at most
  bool refine_principal_point = true;   // a final bundle adjustment that also refines cx, cy
  double min_registered = 0.5;          // fraction of photos that must be registered
  int seed = 0;                         // COLMAP's random seed
  std::string colmap = "colmap";        // the COLMAP program (runtime)

  template <class V>
  void Visit(V& v) {
    v("camera_model", camera_model, "COLMAP camera model", "", OptionKind::kResult,
      {"SIMPLE_PINHOLE", "PINHOLE", "SIMPLE_RADIAL", "RADIAL", "OPENCV", "OPENCV_FISHEYE", "FULL_OPENCV"});
    v("single_camera", single_camera,
      "one camera shared by the photos one camera took (by their EXIF make, model, lens and focal length, a video's "
      "frames, and size); false: one for every photo");
    v("matcher", matcher,
      "feature matching: exhaustive (every pair), sequential (neighbours in file-name order, as video frames or a "
      "camera's counter, and keyframes every sequential_overlap / 2 photos with each other, closing loops), vocab_tree "
      "(the most similar photos, by a vocabulary tree built from them: any order), or "
      "auto: exhaustive up to exhaustive_max_images photos (twice as many frames of one video); above, sequential "
      "for the frames of one video or numbered names, else vocab_tree; when too few photos register, the other kind of "
      "matching is added once and the mapping rerun");
    v("exhaustive_max_images", exhaustive_max_images,
      "photos above which auto matching is sequential (one video's frames, numbered names) or by retrieval (others)",
      "images");
    v("sequential_overlap", sequential_overlap, "neighbours each photo is matched with (sequential)", "images");
    v("retrieval_neighbours", retrieval_neighbours,
      "most similar photos each photo is matched with (vocab_tree), and half as many more spread through the next "
      "four times as many",
      "images");
    v("hierarchical_min_images", hierarchical_min_images,
      "photos from which COLMAP's hierarchical mapper maps them (clusters of at most leaf_max_images photos, each "
      "grown by a quarter as many of its neighbours', mapped on their own, as many at once as there are threads, or "
      "each as a job of its own under a scheduler, then merged) instead of its incremental one; 0: never",
      "images");
    v("leaf_max_images", leaf_max_images, "photos in one cluster of the hierarchical mapper at most (8 or more)",
      "images");
    v("max_image_size", max_image_size, "longest image side for feature extraction", "px");
    v("block_images", block_images,
      "under a scheduler, photos one job extracts features from or matches at most: more are extracted, and their "
      "pairs matched, in blocks, each a job of its own, and merged (the same features and matches)",
      "images", OptionKind::kRuntime);
    v("max_num_features", max_num_features,
      "features per photo at most (CPU matching costs the square of it; 2048 matched fox in 66 s against 176 s for "
      "4096, its cameras within 0.01 deg of those)",
      "features");
    v("refine_principal_point", refine_principal_point, "final bundle adjustment that also refines cx, cy");
    v("min_registered", min_registered, "fraction of photos that must be registered, else an error", "",
      OptionKind::kCheck);
    v("seed", seed, "COLMAP's random seed");
    v("colmap", colmap, "the COLMAP program (name on PATH or a path)", "", OptionKind::kRuntime);
  }
  void Check() const;
};

}  // namespace p2n
