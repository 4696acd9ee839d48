#pragma once
// The ingest stage's options (ingest.*), apart from the stage as every stage's are.

#include "pipeline/options.h"

namespace p2n {

struct IngestOptions {
  static constexpr const char* kSection = "ingest";  // its options are ingest.NAME

  int max_image_size = 0;     // Longest image side after downsizing (area filter), in pixels; 0 keeps the size.
  int min_images = 3;         // Fewer usable images than this is an error.
  AutoOrNumber video_frames;  // frames taken from each video; auto: AutoFrameCount

  template <class V>
  void Visit(V& v) {
    v("max_image_size", max_image_size, "longest image side after downsizing (area filter); 0 keeps the size", "px");
    v("video_frames", video_frames,
      "frames taken from each video, the sharpest of each stretch of equal camera motion; auto: five a second of "
      "video, at least 100 and at most 300",
      "frames");
    v("min_images", min_images, "fewer usable images than this is an error", "images", OptionKind::kCheck);
  }
  void Check() const;
};

}  // namespace p2n
