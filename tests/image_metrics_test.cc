// Image error measures with known answers: PSNR of a constant offset, SSIM of identical, inverted and noisy
// images, and the error heat map's end points.

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "base/float_image.h"

namespace p2n::testing {
namespace {

FloatImage Pattern(int width, int height) {
  FloatImage image{width, height, 3, std::vector<float>(size_t(width) * height * 3)};
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < 3; ++c) {
        image.pixels[(size_t(y) * width + x) * 3 + c] = 0.5f + 0.4f * std::sin(0.3f * x + 0.2f * y + c);
      }
    }
  }
  return image;
}

}  // namespace

TEST_CASE("image metrics: PSNR and SSIM have their known values", "[metrics]") {
  const FloatImage a = Pattern(64, 48);
  FloatImage shifted = a;
  for (float& v : shifted.pixels) v += 0.1f;
  CHECK(Psnr(a, shifted) == Approx(20.0).epsilon(1e-4));  // MSE 0.01
  CHECK(Ssim(a, a) == Approx(1.0).epsilon(1e-9));
  // A constant offset leaves contrast and structure: SSIM is the luminance term alone, close to 1.
  CHECK(Ssim(a, shifted) > 0.95);
  FloatImage inverted = a;
  for (float& v : inverted.pixels) v = 1 - v;
  CHECK(Ssim(a, inverted) < -0.5);  // anti-correlated structure
  FloatImage noisy = a;
  std::mt19937 random(1);
  std::normal_distribution<float> noise(0, 0.2f);
  for (float& v : noisy.pixels) v += noise(random);
  const double noisy_ssim = Ssim(a, noisy);
  CHECK(noisy_ssim > 0.05);
  CHECK(noisy_ssim < 0.7);
  CHECK_THROWS_AS(Ssim(a, Pattern(64, 47)), std::invalid_argument);

  // Every channel is treated alike: the SSIM of RGB is the mean of its channels' SSIMs.
  double per_channel = 0;
  for (int c = 0; c < 3; ++c) {
    FloatImage x{a.width, a.height, 1, {}}, y{a.width, a.height, 1, {}};
    for (size_t i = 0; i < a.pixels.size() / 3; ++i) {
      x.pixels.push_back(a.pixels[3 * i + c]);
      y.pixels.push_back(noisy.pixels[3 * i + c]);
    }
    per_channel += Ssim(x, y) / 3;
  }
  CHECK(noisy_ssim == Approx(per_channel).epsilon(1e-9));
  // Flat images: the stabilising constants decide (0 / 0 without them), in every channel.
  const FloatImage flat{16, 16, 3, std::vector<float>(16 * 16 * 3, 0.5f)};
  CHECK(Ssim(flat, flat) == Approx(1.0));
}

TEST_CASE("image metrics: the error heat map is black where equal and bright at the cap", "[metrics]") {
  const FloatImage a = Pattern(8, 8);
  FloatImage b = a;
  for (int c = 0; c < 3; ++c) b.pixels[c] += 0.5f;  // pixel 0 off by 0.5 in every channel
  const FloatImage map = ErrorHeatMap(a, b, 0.25f);
  REQUIRE(map.channels == 3);
  for (int c = 0; c < 3; ++c) CHECK(map.pixels[3 + c] < 0.05f);  // pixel 1: no error, inferno's black
  CHECK(map.pixels[0] > 0.9f);  // pixel 0: beyond the cap, inferno's yellow (red and green high)
  CHECK(map.pixels[1] > 0.9f);
}

}  // namespace p2n::testing
