#pragma once
// Videos, through OpenCV's videoio over FFmpeg. Read as ingest reads them: the frames turned by the rotation a phone
// records (a portrait video decodes portrait); ScanVideo measures every frame in one pass, DecodeFrames decodes the
// chosen ones in a second, so a long video never sits in memory whole. Written as the render stage writes them: MP4,
// H.264 (what browsers play) where FFmpeg has the encoder (VideoWriter).

#include <OpenImageIO/imagebuf.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "base/float_image.h"

namespace p2n {

// Whether ingest reads the file as a video: its extension is mp4, mov, m4v, avi, mkv or webm (any case).
bool IsVideoFile(const std::filesystem::path& path);

// Thumbnails are this wide (and as tall as the frame's shape makes them): enough to see the camera move, too small
// to see noise or compression.
inline constexpr int kThumbnailWidth = 64;

struct VideoScan {
  double fps = 0;
  int width = 0, height = 0;      // of the decoded (turned) frames
  std::vector<double> times;      // each decoded frame's time stamp, in seconds
  std::vector<double> sharpness;  // variance of the Laplacian of the frame's grey values: low when blurred
  std::vector<double> motion;     // ThumbnailDifference from the frame before (0 for the first)
  int thumbnail_height = 0;
  std::vector<std::vector<uint8_t>> thumbnails;  // grey, kThumbnailWidth x thumbnail_height, one a frame

  size_t size() const { return times.size(); }
  // How long the decoded frames last: the last one's time stamp and its own length.
  double seconds() const { return times.empty() ? 0.0 : times.back() + (fps > 0 ? 1 / fps : 0.0); }
};

// Mean absolute difference of two frames' thumbnails, in grey levels (0 to 255).
double ThumbnailDifference(const VideoScan& scan, size_t a, size_t b);

// Decodes the whole video once. UserError naming the file when it cannot be opened as a video (damaged, only
// sound, a format FFmpeg does not read), holds no frames, or ends well before the duration its header gives.
VideoScan ScanVideo(const std::filesystem::path& path);

// Decodes the video again and calls `take(index, frame)` with each frame whose index is in `indices` (ascending),
// as 8-bit RGB. UserError naming the file when a frame of them cannot be decoded.
void DecodeFrames(const std::filesystem::path& path, const std::vector<size_t>& indices,
                  const std::function<void(size_t index, const OIIO::ImageBuf& frame)>& take);

// MP4 video of rendered frames.
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
