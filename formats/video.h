#pragma once
// MP4 video of rendered frames: H.264 (what browsers play) through OpenCV's FFmpeg back end.

#include <filesystem>
#include <memory>
#include <string>

#include "base/float_image.h"

namespace p2n {

class VideoWriter {
 public:
  // Frames must all be width x height (RGB); odd sizes lose their last column or row (H.264 needs even
  // sizes). UserError naming the file when no encoder can write it.
  VideoWriter(const std::filesystem::path& path, int width, int height, double fps);
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  void Add(const FloatImage& frame);
  // Flushes and closes the file.
  void Close();
  // "avc1" (H.264), or "mp4v" (MPEG-4 part 2, which browsers may not play) where FFmpeg has no H.264 encoder.
  const std::string& codec() const { return codec_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string codec_;
};

}  // namespace p2n
