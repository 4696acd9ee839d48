// libFuzzer: video files as ingest reads them (FFmpeg's demuxers and decoders behind OpenCV's videoio, then our
// measures of each frame and the second pass that decodes chosen frames). The first byte picks the extension.
#include <array>
#include <vector>

#include "base/errors.h"
#include "base/video_io.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static constexpr std::array<const char*, 4> kExtensions = {"mp4", "avi", "mkv", "mov"};
  const auto path = p2n::fuzz::ScratchDir() / (std::string("input.") + kExtensions[data[0] % kExtensions.size()]);
  p2n::fuzz::WriteBytes(path, data + 1, size - 1);
  try {
    const p2n::VideoScan scan = p2n::ScanVideo(path);
    if (scan.size() > 1) p2n::ThumbnailDifference(scan, 0, scan.size() - 1);
    std::vector<size_t> indices = {0};
    if (scan.size() > 1) indices.push_back(scan.size() - 1);
    p2n::DecodeFrames(path, indices, [](size_t, const OIIO::ImageBuf&) {});
  } catch (const p2n::UserError&) {
  }
  return 0;
}
