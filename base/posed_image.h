#pragma once
// Posed photos as the optimisers read them (a field's trainer and the splats' alike): the camera, the 8-bit
// pixels, and the background they were composited on.

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "base/camera.h"
#include "base/float_image.h"

namespace p2n {

// A sparse point a training view sees (the structure from motion's): where it appears (pixels), how far it lies along
// the ray through there (world units), and the point's reprojection error (pixels): free depth for that pixel.
struct DepthPoint {
  float u = 0, v = 0, distance = 0, error = 0;
};

// One posed image. Cameras are in the normalised world (transforms.json's frame); pixels are 8-bit RGB or
// RGBA (straight alpha), row-major.
struct TrainView {
  PinholeCamera camera;
  double near = -1, far = -1;  // world units; negative: the whole box
  int channels = 3;
  std::vector<uint8_t> pixels;
  std::string name;
  std::vector<DepthPoint> depth_points;  // loaded for the depth loss only

  // The size its pixels have in memory (whether or not they are loaded).
  size_t PixelBytes() const { return size_t(camera.width) * camera.height * channels; }

  // Channel c (0-2) of a pixel (index y * width + x) as a float in [0, 1], over `background` by its alpha.
  float OnBackground(size_t pixel, int c, float background) const {
    const uint8_t* value = pixels.data() + pixel * channels;
    const float alpha = channels == 4 ? value[3] / 255.0f : 1.0f;
    return alpha * (value[c] / 255.0f) + (1 - alpha) * background;
  }
};

// A copy of `view` but for its pixels (a view whose pixels are read later, or lent).
TrainView WithoutPixels(const TrainView& view);

// The photo as floats (RGB), composited on `background` where it has alpha: what a render is compared with.
FloatImage PhotoOnBackground(const TrainView& view, const std::array<float, 3>& background);
// The first of `views` with an alpha channel (composited on a background the trainers must keep), or null.
const TrainView* FirstWithAlpha(const std::vector<TrainView>& views);

struct TrainingData {
  std::vector<TrainView> train, heldout;
  std::array<float, 3> background{1, 1, 1};  // behind the scene: the known colour, or where a learnt one starts
  bool background_known = false;             // the images were rendered or composited on `background`
  // Held-out view v's pixels where `heldout` holds none (photos too many for memory, stages/photo_memory.h): an
  // evaluation reads them a view at a time.
  std::function<std::vector<uint8_t>(size_t)> read_heldout;
};

// Held-out view v of `data` with its pixels: the view itself, or a copy of it in `scratch` with them read
// (TrainingData::read_heldout).
const TrainView& HeldoutView(const TrainingData& data, size_t v, TrainView* scratch);

}  // namespace p2n
