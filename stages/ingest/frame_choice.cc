#include "stages/ingest/frame_choice.h"

#include <algorithm>
#include <cmath>

namespace p2n {
namespace {

constexpr double kFramesPerSecond = 5;
constexpr int kMinAutoFrames = 100, kMaxAutoFrames = 300;

// The sharpest frame of each of `count` windows of equal motion; windows the motion jumps over stay empty.
std::vector<size_t> SharpestOfWindows(const VideoScan& scan, int count) {
  std::vector<double> travelled(scan.size(), 0.0);  // the motion summed up to each frame
  for (size_t i = 1; i < scan.size(); ++i) travelled[i] = travelled[i - 1] + scan.motion[i];
  const double window = travelled.back() / count;
  std::vector<size_t> taken;
  long current = -1;  // the window of the frame last looked at
  for (size_t i = 0; i < scan.size(); ++i) {
    const long w = window > 0 ? std::min<long>(count - 1, static_cast<long>(travelled[i] / window)) : 0;
    if (w != current) {
      taken.push_back(i);
      current = w;
    } else if (scan.sharpness[i] > scan.sharpness[taken.back()]) {
      taken.back() = i;
    }
  }
  return taken;
}

}  // namespace

int AutoFrameCount(double seconds, size_t frames) {
  const int by_length =
      std::clamp(static_cast<int>(std::lround(seconds * kFramesPerSecond)), kMinAutoFrames, kMaxAutoFrames);
  return static_cast<int>(std::min<size_t>(by_length, frames));
}

FrameChoice ChooseFrames(const VideoScan& scan, int count) {
  const std::vector<size_t> sharpest = SharpestOfWindows(scan, std::max(1, count));
  std::vector<double> steps;
  for (size_t k = 1; k < sharpest.size(); ++k) steps.push_back(ThumbnailDifference(scan, sharpest[k - 1], sharpest[k]));
  double median = 0;
  if (!steps.empty()) {
    std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
    median = steps[steps.size() / 2];
  }
  const double repeat_below = std::max(kRepeatShare * median, kRepeatGreyLevels);
  FrameChoice choice;
  for (size_t frame : sharpest) {
    if (!choice.taken.empty() && ThumbnailDifference(scan, choice.taken.back(), frame) < repeat_below) {
      choice.repeats.push_back({frame, choice.taken.back()});
    } else {
      choice.taken.push_back(frame);
    }
  }
  return choice;
}

}  // namespace p2n
