#include "base/video_io.h"

#include <opencv2/core.hpp>
#include <opencv2/core/version.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

// A video whose frames stop before this share of the duration its header gives is taken to be cut short.
constexpr double kTruncatedShare = 0.9;

// A video opened for reading, and how far its frames must be turned clockwise to stand as recorded.
struct OpenVideo {
  cv::VideoCapture capture;
  int clockwise_turn = 0;  // 0, 90, 180 or 270 degrees

  cv::Mat Upright(const cv::Mat& frame) const {
    if (clockwise_turn == 0) return frame;
    cv::Mat out;
    cv::rotate(frame, out,
               clockwise_turn == 90    ? cv::ROTATE_90_CLOCKWISE
               : clockwise_turn == 180 ? cv::ROTATE_180
                                       : cv::ROTATE_90_COUNTERCLOCKWISE);
    return out;
  }
};

// The multiple of 90 degrees in [0, 360) nearest to a rotation the file states (any number a damaged file holds).
int NearestQuarterTurn(double degrees) {
  if (!std::isfinite(degrees)) return 0;
  const double quarters = std::round(std::fmod(degrees, 360.0) / 90.0);
  return static_cast<int>((static_cast<long>(quarters) % 4 + 4) % 4) * 90;
}

OpenVideo Open(const fs::path& path) {
  OpenVideo video;
  try {
    video.capture.open(path.string(), cv::CAP_FFMPEG);
  } catch (const cv::Exception&) {
    video.capture.release();
  }
  if (!video.capture.isOpened()) {
    throw UserError(
        format("cannot open '{}' as a video: it is damaged, holds only sound, or is in a format FFmpeg "
               "does not read; convert it to an MP4 (H.264) or take it out of the folder",
               path.string()));
  }
  // We turn the frames ourselves: OpenCV 4.6.0 (Debian 12's) reads a phone's rotation with its sign turned and
  // would stand a portrait video on its head (opencv/opencv issue 22088, fixed in 4.7).
  video.capture.set(cv::CAP_PROP_ORIENTATION_AUTO, 0);
  double turn = video.capture.get(cv::CAP_PROP_ORIENTATION_META);
#if CV_VERSION_MAJOR == 4 && CV_VERSION_MINOR == 6
  turn = -turn;
#endif
  video.clockwise_turn = NearestQuarterTurn(turn);
  return video;
}

std::vector<uint8_t> Thumbnail(const cv::Mat& grey, int height) {
  cv::Mat small;
  cv::resize(grey, small, cv::Size(kThumbnailWidth, height), 0, 0, cv::INTER_AREA);
  return std::vector<uint8_t>(small.datastart, small.dataend);
}

double Sharpness(const cv::Mat& grey) {
  cv::Mat laplacian;
  cv::Laplacian(grey, laplacian, CV_32F);
  cv::Scalar mean, deviation;
  cv::meanStdDev(laplacian, mean, deviation);
  return deviation[0] * deviation[0];
}

// Adds one decoded frame's measures to the scan.
void Measure(const cv::Mat& frame, double time, VideoScan* scan) {
  cv::Mat grey;
  cv::cvtColor(frame, grey, cv::COLOR_BGR2GRAY);
  if (scan->thumbnails.empty()) {
    scan->width = frame.cols;
    scan->height = frame.rows;
    scan->thumbnail_height =
        std::max(1, static_cast<int>(std::lround(kThumbnailWidth * double(frame.rows) / frame.cols)));
  }
  scan->times.push_back(time);
  scan->sharpness.push_back(Sharpness(grey));
  scan->thumbnails.push_back(Thumbnail(grey, scan->thumbnail_height));
  const size_t last = scan->size() - 1;
  scan->motion.push_back(last == 0 ? 0.0 : ThumbnailDifference(*scan, last - 1, last));
}

}  // namespace

bool IsVideoFile(const fs::path& path) {
  static const std::set<std::string> kExtensions = {"mp4", "mov", "m4v", "avi", "mkv", "webm"};
  return kExtensions.count(LowerExtension(path)) > 0;
}

double ThumbnailDifference(const VideoScan& scan, size_t a, size_t b) {
  const std::vector<uint8_t>& first = scan.thumbnails.at(a);
  const std::vector<uint8_t>& second = scan.thumbnails.at(b);
  double sum = 0;
  for (size_t i = 0; i < first.size(); ++i) sum += std::abs(int(first[i]) - int(second[i]));
  return first.empty() ? 0.0 : sum / first.size();
}

VideoScan ScanVideo(const fs::path& path) {
  OpenVideo video = Open(path);
  cv::VideoCapture& capture = video.capture;
  VideoScan scan;
  scan.fps = capture.get(cv::CAP_PROP_FPS);
  // The header's frame count (estimated from its duration in some containers) over the rate: its duration.
  const double claimed_seconds = scan.fps > 0 ? capture.get(cv::CAP_PROP_FRAME_COUNT) / scan.fps : 0;
  cv::Mat frame;
  while (capture.read(frame) && !frame.empty()) {
    const double stamp = capture.get(cv::CAP_PROP_POS_MSEC) / 1000.0;
    const double counted = scan.fps > 0 ? scan.size() / scan.fps : 0.0;
    const bool stamped = std::isfinite(stamp) && (scan.times.empty() ? stamp >= 0 : stamp > scan.times.back());
    Measure(video.Upright(frame), stamped ? stamp : counted, &scan);
  }
  if (scan.size() == 0) {
    throw UserError(
        format("'{}' holds no video frames that FFmpeg can decode; check that it plays, or take it out "
               "of the folder",
               path.string()));
  }
  // By time, not by frame count: a variable frame rate makes a count estimated from the duration too high.
  if (scan.seconds() < kTruncatedShare * claimed_seconds) {
    throw UserError(
        format("'{}' ends after {:.1f} s ({} frames) of the {:.1f} s its header gives: the file is cut "
               "short (an interrupted copy or download?); copy it again from the camera",
               path.string(), scan.seconds(), scan.size(), claimed_seconds));
  }
  return scan;
}

void DecodeFrames(const fs::path& path, const std::vector<size_t>& indices,
                  const std::function<void(size_t, const OIIO::ImageBuf&)>& take) {
  OpenVideo video = Open(path);
  cv::Mat frame, rgb;
  size_t next = 0;
  for (size_t index = 0; next < indices.size(); ++index) {
    if (!video.capture.grab()) {
      throw UserError(
          format("'{}' changed while it was read: frame {} cannot be decoded again", path.string(), indices[next]));
    }
    if (index != indices[next]) continue;
    video.capture.retrieve(frame);
    cv::cvtColor(video.Upright(frame), rgb, cv::COLOR_BGR2RGB);
    OIIO::ImageBuf image(OIIO::ImageSpec(rgb.cols, rgb.rows, 3, OIIO::TypeDesc::UINT8));
    image.set_pixels(OIIO::ROI(0, rgb.cols, 0, rgb.rows, 0, 1, 0, 3), OIIO::TypeDesc::UINT8, rgb.data);
    take(index, image);
    ++next;
  }
}

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
