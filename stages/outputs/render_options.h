#pragma once
// The render stage's options (render.*), apart from the stage so that the report includes them alone.

#include <string>

#include "base/enum_names.h"
#include "pipeline/options.h"
#include "stages/stage_reports.h"

namespace p2n {

inline constexpr int kDefaultMaxPathWidth = 320;

struct RenderStageOptions {
  static constexpr const char* kSection = "render";  // its options are render.NAME

  bool heldout = true;                        // render and evaluate the held-out views
  RenderSource source = RenderSource::kAuto;  // auto: the splats when they score within 0.5 dB of the field
  PathChoice path = PathChoice::kAuto;        // auto: spiral for LLFF data and one-sided captures
  std::string path_file;                      // cameras of the path (transforms.json layout) when path = file
  int frames = 60;                            // frames of an orbit or spiral
  int width = 0;                              // path frames' width in pixels (height by the aspect); 0: the photos',
                                              // at most kDefaultMaxPathWidth
  AutoOrNumber elevation;                     // orbit: degrees above the horizontal; auto: the cameras' mean
  double radius = 0;                          // orbit: distance from the centre (normalised units); spiral: amplitude
                                              // (times the cameras' spread); 0: the cameras' mean distance, or 1
  double fps = 24;                            // video frames per second
  bool video = true;                          // write video.mp4 of the path
  bool depth = true;                          // write depth and opacity images of the path
  bool exr = false;                           // also write linear float EXR images (RGB and depth)
  double step_scale = 0;  // sample spacing as a multiple of the model's (training) step; 0: by the scene

  template <class V>
  void Visit(V& v) {
    v("heldout", heldout, "render the held-out views and compare them with their photos (PSNR, SSIM)");
    v("source", source,
      "what renders the views: field (ray marching), splats (rasterized, tens of times faster) or auto: the "
      "splats when their held-out PSNR is within 0.5 dB of the field's, else the field");
    v("path", path,
      "camera path: orbit (round the centre, over the arc of directions the photos were taken from, there and "
      "back; all the way round when they surround it), spiral (in front of the capture), file, none; auto: spiral "
      "for LLFF data and for photos taken from one side (within 30 degrees), else orbit");
    v("path_file", path_file,
      "cameras of the path when path is file (transforms.json layout, e.g. an "
      "edited path.json)");
    v("frames", frames, "frames of an orbit or spiral", "frames");
    v("width", width, "width of the path frames; 0: the photos' width, at most 320", "pixels");
    v("elevation", elevation, "orbit: height above the horizontal; auto: the cameras' mean", "degrees");
    v("radius", radius,
      "orbit: distance from the centre (normalised units); spiral: amplitude in the cameras' "
      "spread; 0: the cameras' mean distance (orbit) or 1 (spiral)");
    v("fps", fps, "video frames per second", "frames/s");
    v("video", video, "write video.mp4 of the path (H.264)");
    v("depth", depth, "write depth and opacity images of the path");
    v("exr", exr, "also write linear 32-bit float EXR images (RGB and depth)");
    v("step_scale", step_scale,
      "sample spacing as a multiple of the model's (below 1: finer and slower); 0: by the scene, 0.5 for bounded "
      "scenes (sharp surfaces) and 1 for unbounded ones");
  }
  void Check() const;
};

}  // namespace p2n
