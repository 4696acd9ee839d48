#include "base/posed_image.h"

#include <stdexcept>

namespace p2n {

FloatImage PhotoOnBackground(const TrainView& view, const std::array<float, 3>& background) {
  FloatImage image{view.camera.width, view.camera.height, 3, {}};
  const size_t pixels = size_t(image.width) * image.height;
  image.pixels.resize(3 * pixels);
  for (size_t i = 0; i < pixels; ++i) {
    for (int c = 0; c < 3; ++c) image.pixels[3 * i + c] = view.OnBackground(i, c, background[c]);
  }
  return image;
}

TrainView WithoutPixels(const TrainView& view) {
  return {view.camera, view.near, view.far, view.channels, {}, view.name, view.depth_points};
}

const TrainView* FirstWithAlpha(const std::vector<TrainView>& views) {
  for (const TrainView& view : views) {
    if (view.channels == 4) return &view;
  }
  return nullptr;
}

const TrainView& HeldoutView(const TrainingData& data, size_t v, TrainView* scratch) {
  const TrainView& view = data.heldout.at(v);
  if (!view.pixels.empty()) return view;
  if (!data.read_heldout) throw std::logic_error("a held-out view has no pixels and nothing to read them with");
  *scratch = WithoutPixels(view);
  scratch->pixels = data.read_heldout(v);
  return *scratch;
}

}  // namespace p2n
