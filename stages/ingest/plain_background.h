#pragma once
// Recognises a dataset rendered or composited on a plain background: when the border pixels of every image share
// one colour, that colour is what a ray that ends on nothing shows, and the trainers keep it fixed rather than
// learning it (a learnt background can drift while the field paints the true one as fog in front of it).

#include <OpenImageIO/imagebuf.h>

#include <array>
#include <optional>
#include <vector>

namespace p2n {

using Rgb = std::array<float, 3>;

// The pixels of the image's outermost `width` rows and columns as RGB in [0, 1] (grey repeated; alpha ignored).
std::vector<Rgb> BorderPixels(const OIIO::ImageBuf& image, int width = 2);

// The colour the pixels share: their per-channel median, when at least `share` of them lie within `tolerance` of it
// in every channel; none otherwise (photos, whose borders show the scene).
std::optional<Rgb> SharedColour(std::vector<Rgb> pixels, float tolerance = 4.0f / 255, double share = 0.98);

}  // namespace p2n
