#include "stages/ingest/ingest_video.h"

#include <cmath>

#include "base/errors.h"
#include "base/format.h"
#include "base/image_io.h"
#include "base/video_io.h"
#include "stages/ingest/frame_choice.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

double Rounded(double value, double step) { return std::round(value / step) * step; }

IngestedImage WriteFrame(const fs::path& file, size_t index, double time, const OIIO::ImageBuf& frame,
                         const fs::path& images_dir, int max_image_size) {
  IngestedImage out;
  out.source = file.filename().string();
  out.name = format("{}_{:05d}.jpg", file.stem().string(), index);
  out.camera = "video " + out.source;
  out.frame = index;
  out.time = time;
  const OIIO::ImageBuf image = DownsizeAndDescribe(frame, max_image_size, &out);
  const std::string error = WriteImage(image, images_dir / out.name);
  if (!error.empty()) throw UserError(error);
  return out;
}

}  // namespace

OIIO::ImageBuf DownsizeAndDescribe(const OIIO::ImageBuf& decoded, int max_image_size, IngestedImage* out) {
  out->fingerprint = PixelFingerprint(decoded);
  out->source_width = decoded.spec().width;
  out->source_height = decoded.spec().height;
  OIIO::ImageBuf image = DownsizeToFit(decoded, max_image_size);
  out->width = image.spec().width;
  out->height = image.spec().height;
  out->channels = image.spec().nchannels;
  return image;
}

VideoIngest IngestVideo(const fs::path& file, const fs::path& images_dir, std::optional<int> frames,
                        int max_image_size) {
  const VideoScan scan = ScanVideo(file);
  VideoIngest out;
  IngestedVideo& video = out.video;
  video.file = file.filename().string();
  video.frames = scan.size();
  video.fps = scan.fps;
  video.seconds = scan.seconds();
  video.width = scan.width;
  video.height = scan.height;
  for (double sharpness : scan.sharpness) video.sharpness.push_back(Rounded(sharpness, 0.01));
  const FrameChoice choice = ChooseFrames(scan, frames.value_or(AutoFrameCount(video.seconds, scan.size())));
  for (const auto& [index, of] : choice.repeats) video.repeats.push_back({index, of});
  DecodeFrames(file, choice.taken, [&](size_t index, const OIIO::ImageBuf& frame) {
    const double time = Rounded(scan.times[index], 0.001);
    out.images.push_back(WriteFrame(file, index, time, frame, images_dir, max_image_size));
    video.taken.push_back({index, time, out.images.back().name});
  });
  return out;
}

}  // namespace p2n
