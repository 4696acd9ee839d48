#include "base/photo_window.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

#include "base/format.h"

namespace p2n {

size_t PhotoWindow::WindowSize(const std::vector<TrainView>& views, double bytes) {
  size_t largest = 0;
  for (const TrainView& view : views) largest = std::max(largest, view.PixelBytes());
  const double fit = largest > 0 ? std::floor(bytes / static_cast<double>(largest)) : 0;
  const size_t size = static_cast<size_t>(fit * 4 / 5);  // and a quarter of that being read
  if (views.empty() || size < kMinViews) {
    throw std::invalid_argument(format("{:.2f} MB hold {:.0f} of the largest photos ({:.2f} MB); a window needs {}",
                                       bytes / 1048576, fit, largest / 1048576.0, kMinViews + 1));
  }
  return std::min(size, views.size());
}

PhotoWindow::PhotoWindow(std::vector<TrainView>* views, Loader load, double bytes, uint64_t seed)
    : views_(views), load_(std::move(load)), size_(WindowSize(*views, bytes)) {
  stride_ = std::max<size_t>(1, size_ / 4);
  order_.resize(views->size());
  std::iota(order_.begin(), order_.end(), size_t{0});
  std::mt19937_64 random(seed ^ 0x70686f746f73ULL);
  std::shuffle(order_.begin(), order_.end(), random);
}

PhotoWindow::~PhotoWindow() {
  if (next_pixels_.valid()) next_pixels_.wait();
}

std::vector<size_t> PhotoWindow::Window(int64_t move) const {
  std::vector<size_t> window(size_);
  const size_t first = static_cast<size_t>(move) * stride_ % order_.size();
  for (size_t i = 0; i < size_; ++i) window[i] = order_[(first + i) % order_.size()];
  return window;
}

std::vector<std::vector<uint8_t>> PhotoWindow::Read(const std::vector<size_t>& views) const {
  std::vector<std::vector<uint8_t>> pixels;
  for (const size_t v : views) pixels.push_back(load_(v));
  return pixels;
}

void PhotoWindow::StartReading(int64_t move) {
  const std::vector<size_t> now = Window(move - 1);
  next_views_.clear();
  for (const size_t v : Window(move)) {
    if (std::find(now.begin(), now.end(), v) == now.end()) next_views_.push_back(v);
  }
  next_move_ = move;
  next_pixels_ = std::async(std::launch::async, [this, views = next_views_] { return Read(views); });
}

bool PhotoWindow::MoveTo(int step) {
  const int64_t move = step / kStepsPerMove;
  if (move == move_) return false;
  const std::vector<size_t> window = Window(move);
  const bool read_ahead = next_pixels_.valid() && next_move_ == move;
  if (!read_ahead && next_pixels_.valid()) next_pixels_.wait();  // a jump (the first move, a resumed run)
  for (const size_t v : resident_) {
    if (std::find(window.begin(), window.end(), v) == window.end()) std::vector<uint8_t>().swap((*views_)[v].pixels);
  }
  std::vector<size_t> reading;
  std::vector<std::vector<uint8_t>> pixels;
  if (read_ahead) {
    reading = next_views_;
    pixels = next_pixels_.get();
  } else {
    next_pixels_ = {};
    for (const size_t v : window) {
      if ((*views_)[v].pixels.empty()) reading.push_back(v);
    }
    pixels = Read(reading);
  }
  for (size_t i = 0; i < reading.size(); ++i) {
    TrainView& view = (*views_)[reading[i]];
    if (pixels[i].size() != view.PixelBytes()) {
      throw std::invalid_argument(format("photo {} changed size while the field trained", view.name));
    }
    view.pixels = std::move(pixels[i]);
  }
  resident_ = window;
  move_ = move;
  StartReading(move + 1);
  return true;
}

}  // namespace p2n
