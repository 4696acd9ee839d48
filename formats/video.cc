#include "formats/video.h"

#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cmath>

#include "base/errors.h"
#include "base/format.h"

namespace p2n {

struct VideoWriter::Impl {
  cv::VideoWriter writer;
  cv::Size size;
};

VideoWriter::VideoWriter(const std::filesystem::path& path, int width, int height, double fps)
    : impl_(std::make_unique<Impl>()) {
  impl_->size = cv::Size(width & ~1, height & ~1);
  if (impl_->size.width < 2 || impl_->size.height < 2) {
    throw UserError(format("cannot write a {}x{} video '{}'", width, height, path.string()));
  }
  // H.264 plays everywhere; MPEG-4 part 2 is the fallback of an FFmpeg built without x264.
  for (const char* codec : {"avc1", "mp4v"}) {
    const int fourcc = cv::VideoWriter::fourcc(codec[0], codec[1], codec[2], codec[3]);
    if (impl_->writer.open(path.string(), cv::CAP_FFMPEG, fourcc, fps, impl_->size)) {
      codec_ = codec;
      break;
    }
  }
  if (!impl_->writer.isOpened()) {
    throw UserError(
        format("cannot write the video '{}': OpenCV's FFmpeg back end has no H.264 or MPEG-4 encoder "
               "(install Debian's libopencv-videoio406 with FFmpeg), or the folder is not writable",
               path.string()));
  }
}

VideoWriter::~VideoWriter() = default;

void VideoWriter::Add(const FloatImage& frame) {
  P2N_CHECK(frame.width >= impl_->size.width && frame.height >= impl_->size.height && frame.channels >= 3,
            "a video frame smaller than the video");
  cv::Mat bgr(impl_->size, CV_8UC3);
  for (int y = 0; y < impl_->size.height; ++y) {
    for (int x = 0; x < impl_->size.width; ++x) {
      const float* rgb = &frame.pixels[(size_t(y) * frame.width + x) * frame.channels];
      for (int c = 0; c < 3; ++c) {
        bgr.at<cv::Vec3b>(y, x)[2 - c] = static_cast<uint8_t>(std::lround(255 * std::clamp(rgb[c], 0.0f, 1.0f)));
      }
    }
  }
  impl_->writer.write(bgr);
}

void VideoWriter::Close() { impl_->writer.release(); }

}  // namespace p2n
