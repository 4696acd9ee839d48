#include "nerf/float_image.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "nerf/image_io.h"

namespace p2n {

void SaveFloatImage(const FloatImage& image, const std::filesystem::path& path, bool sixteen_bits) {
  OIIO::ImageBuf buffer(OIIO::ImageSpec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT),
                        const_cast<float*>(image.pixels.data()));
  OIIO::ImageBuf quantised(OIIO::ImageSpec(image.width, image.height, image.channels,
                                           sixteen_bits ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8));
  quantised.copy_pixels(OIIO::ImageBufAlgo::clamp(buffer, 0.0f, 1.0f));
  const std::string error = WriteImage(quantised, path);
  if (!error.empty()) throw std::runtime_error(error);
}

double Psnr(const FloatImage& a, const FloatImage& b) {
  if (a.pixels.size() != b.pixels.size()) throw std::invalid_argument("PSNR of images of different sizes");
  double squared_error = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const double d = a.pixels[i] - b.pixels[i];
    squared_error += d * d;
  }
  return -10 * std::log10(std::max(squared_error / a.pixels.size(), 1e-20));
}

}  // namespace p2n
