#include "stages/ingest/plain_background.h"

#include <algorithm>
#include <cmath>

namespace p2n {

std::vector<Rgb> BorderPixels(const OIIO::ImageBuf& image, int width) {
  const OIIO::ImageSpec& spec = image.spec();
  std::vector<float> values(size_t(spec.width) * spec.height * spec.nchannels);
  image.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, values.data());
  const int colours = spec.nchannels >= 3 ? 3 : 1;
  std::vector<Rgb> border;
  for (int y = 0; y < spec.height; ++y) {
    const bool edge_row = y < width || y >= spec.height - width;
    for (int x = 0; x < spec.width; ++x) {
      if (!edge_row && x >= width && x < spec.width - width) x = spec.width - width;  // skip the interior
      const float* pixel = values.data() + (size_t(y) * spec.width + x) * spec.nchannels;
      border.push_back({pixel[0], pixel[colours == 3 ? 1 : 0], pixel[colours == 3 ? 2 : 0]});
    }
  }
  return border;
}

std::optional<Rgb> SharedColour(std::vector<Rgb> pixels, float tolerance, double share) {
  if (pixels.empty()) return std::nullopt;
  Rgb median{};
  std::vector<float> channel(pixels.size());
  for (int c = 0; c < 3; ++c) {
    for (size_t i = 0; i < pixels.size(); ++i) channel[i] = pixels[i][c];
    std::nth_element(channel.begin(), channel.begin() + channel.size() / 2, channel.end());
    median[c] = channel[channel.size() / 2];
  }
  const size_t near = std::count_if(pixels.begin(), pixels.end(), [&](const Rgb& p) {
    return std::abs(p[0] - median[0]) <= tolerance && std::abs(p[1] - median[1]) <= tolerance &&
           std::abs(p[2] - median[2]) <= tolerance;
  });
  if (near < share * pixels.size()) return std::nullopt;
  return median;
}

}  // namespace p2n
