#pragma once
// Training photos too many for memory: a window over them holds a few at a time, within a byte budget
// (train.photo_memory). The window runs over the views in a shuffled order (consecutive photos of a capture see
// the same part of the scene; a shuffled window sees all of it) and moves on by a quarter of its views every
// kStepsPerMove training steps, the next quarter read on another thread while the field trains (the train stage
// reads them from their decoded copy, decoded_photos.h). Where the window stands depends on the step alone, so a
// seed and a step count give the same model and a resumed run reads the photos it would have read.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <future>
#include <vector>

#include "base/posed_image.h"

namespace p2n {

class PhotoWindow {
 public:
  // A view's pixels (TrainView::pixels of its PixelBytes()); may throw, and is called from another thread.
  using Loader = std::function<std::vector<uint8_t>(size_t view)>;

  static constexpr int kStepsPerMove = 32;
  static constexpr size_t kMinViews = 4;  // in the window; a fifth of the budget more for the next quarter

  // Over `views` (their pixels released as the window leaves them), within `bytes`. Nothing is read before MoveTo().
  PhotoWindow(std::vector<TrainView>* views, Loader load, double bytes, uint64_t seed);
  // The views a window over `views` within `bytes` holds; std::invalid_argument when `bytes` holds fewer than
  // kMinViews + 1 of the largest (a fifth of the budget is for the views being read).
  static size_t WindowSize(const std::vector<TrainView>& views, double bytes);
  ~PhotoWindow();  // waits for a read under way
  PhotoWindow(const PhotoWindow&) = delete;
  PhotoWindow& operator=(const PhotoWindow&) = delete;

  // Puts the window where it stands at training step `step` (waiting for the read of its views, or reading them
  // now after a jump) and starts reading the next move's; returns whether it moved. Rethrows the loader's error.
  bool MoveTo(int step);
  // The views with pixels in memory, in the window's order.
  const std::vector<size_t>& resident() const { return resident_; }
  size_t size() const { return size_; }      // views in the window
  size_t stride() const { return stride_; }  // views it moves by

 private:
  std::vector<size_t> Window(int64_t move) const;
  std::vector<std::vector<uint8_t>> Read(const std::vector<size_t>& views) const;
  void StartReading(int64_t move);

  std::vector<TrainView>* views_;
  Loader load_;
  std::vector<size_t> order_;
  size_t size_ = 0, stride_ = 0;
  int64_t move_ = -1;
  std::vector<size_t> resident_;
  int64_t next_move_ = -1;          // the move being read ahead
  std::vector<size_t> next_views_;  // the views it adds
  std::future<std::vector<std::vector<uint8_t>>> next_pixels_;
};

}  // namespace p2n
