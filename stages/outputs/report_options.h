#pragma once
// The report stage's options (report.*), apart from the stage as every stage's are.

#include "pipeline/options.h"

namespace p2n {

struct ReportOptions {
  static constexpr const char* kSection = "report";  // its options are report.NAME

  int image_width = 480;    // images are embedded at most this wide
  bool embed_video = true;  // embed video.mp4 in the page (else link to it)

  template <class V>
  void Visit(V& v) {
    v("image_width", image_width, "images are embedded at most this wide", "pixels");
    v("embed_video", embed_video, "embed the video in the page (else link to the render stage's video)");
  }
  void Check() const;
};

}  // namespace p2n
