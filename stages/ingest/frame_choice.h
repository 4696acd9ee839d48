#pragma once
// Which frames of a video ingest keeps. A video is split into windows of equal motion (so that a camera standing
// still adds no frames and a fast pan adds many), the sharpest frame of each window is taken (motion blur is the
// commonest failure of a video capture), and a taken frame that nearly repeats the one kept before it is dropped.

#include <cstddef>
#include <utility>
#include <vector>

#include "base/video_io.h"

namespace p2n {

// A taken frame is dropped as a repeat when its thumbnail differs from the kept frame before it by less than this
// share of the median difference between neighbouring taken frames, or by less than kRepeatGreyLevels.
inline constexpr double kRepeatShare = 0.25;
inline constexpr double kRepeatGreyLevels = 0.5;

// ingest.video_frames auto: five frames a second of video, at least 100 and at most 300, never more than it has.
int AutoFrameCount(double seconds, size_t frames);

struct FrameChoice {
  std::vector<size_t> taken;                       // frame indices, ascending
  std::vector<std::pair<size_t, size_t>> repeats;  // {a dropped frame, the kept frame it nearly repeats}
};

// Up to `count` frames of the scanned video, chosen as above.
FrameChoice ChooseFrames(const VideoScan& scan, int count);

}  // namespace p2n
