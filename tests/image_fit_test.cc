// Fitting one image (issue 6): a smooth image is learnt to a high PSNR in a few hundred steps; a pattern of
// high frequency needs the positional encoding.

#include <OpenImageIO/imagebuf.h>
#include <catch2/catch.hpp>

#include "nerf/image_fit.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace {

FloatImage Ramp(int size) {
  FloatImage image{size, size, 3, {}};
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      image.pixels.insert(image.pixels.end(), {(x + 0.5f) / size, (y + 0.5f) / size, 0.5f});
    }
  }
  return image;
}

// Black and white squares of 2 x 2 pixels: the finest detail an image can have, nearly.
FloatImage Checker(int size) {
  FloatImage image{size, size, 1, {}};
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) image.pixels.push_back(((x / 2 + y / 2) % 2) ? 1.0f : 0.0f);
  }
  return image;
}

ImageFitOptions SmallPe(int levels, int steps) {
  ImageFitOptions options;
  options.model = FitModel::kPe;
  options.pe_levels = levels;
  options.width = 128;
  options.batch_size = 4096;
  options.time_budget = 0;
  options.max_steps = steps;
  options.snapshot_steps = "";
  return options;
}

}  // namespace

TEST_CASE("a smooth gradient image is fitted above 40 dB within a few hundred steps", "[fit]") {
  const FloatImage ramp = Ramp(48);
  const ImageFitResult pe = FitImage(SmallPe(10, 300), ramp);
  CHECK(pe.psnr > 40);
  ImageFitOptions grid = SmallPe(10, 300);
  grid.model = FitModel::kHashGrid;
  grid.width = 0;
  const ImageFitResult hashed = FitImage(grid, ramp);
  CHECK(hashed.psnr > 40);
  CHECK(hashed.model_config["encoding"]["otype"] == "HashGrid");
  // The curve is logged with increasing time and ends at the last step.
  CHECK(pe.curve.front().step == 0);
  CHECK(pe.curve.back().step == 300);
}

TEST_CASE("the positional encoding is what lets the MLP fit fine detail", "[fit]") {
  const FloatImage checker = Checker(32);
  const ImageFitResult raw = FitImage(SmallPe(0, 300), checker);
  const ImageFitResult encoded = FitImage(SmallPe(10, 300), checker);
  INFO("raw " << raw.psnr << " dB, encoded " << encoded.psnr << " dB");
  CHECK(raw.psnr < 10);  // about the 6 dB of a flat grey
  CHECK(encoded.psnr > 30);
}

TEST_CASE("images load as grey or RGB, with alpha composited over white or ignored", "[fit]") {
  TempDir dir;
  OIIO::ImageSpec spec(2, 1, 4, OIIO::TypeDesc::UINT16);
  spec.attribute("oiio:UnassociatedAlpha", 1);  // write the colour of the transparent pixel as it is
  OIIO::ImageBuf rgba(spec);
  const float transparent_red[4] = {1, 0, 0, 0}, opaque_blue[4] = {0, 0, 1, 1};
  rgba.setpixel(0, 0, transparent_red);
  rgba.setpixel(1, 0, opaque_blue);
  REQUIRE(rgba.write((dir / "rgba16.png").string()));
  const FloatImage composited = LoadImageForFit(dir / "rgba16.png", FitAlpha::kComposite);
  REQUIRE(composited.channels == 3);
  CHECK(composited.pixels == std::vector<float>{1, 1, 1, 0, 0, 1});
  const FloatImage ignored = LoadImageForFit(dir / "rgba16.png", FitAlpha::kIgnore);
  CHECK(ignored.pixels == std::vector<float>{1, 0, 0, 0, 0, 1});
  OIIO::ImageBuf grey(OIIO::ImageSpec(3, 2, 1, OIIO::TypeDesc::UINT8));
  REQUIRE(grey.write((dir / "grey.png").string()));
  CHECK(LoadImageForFit(dir / "grey.png", FitAlpha::kComposite).channels == 1);
  WriteText(dir / "bad.png", "not an image");
  CHECK_THROWS_WITH(LoadImageForFit(dir / "bad.png", FitAlpha::kComposite), Catch::Contains("bad.png"));
}

TEST_CASE("fit options are checked and name the option", "[fit]") {
  ImageFitOptions options;
  options.batch_size = 0;
  CHECK_THROWS_WITH(options.Check(), "fit.batch_size must be in 1..16777216, not 0");
  options = ImageFitOptions();
  options.time_budget = 0;
  CHECK_THROWS_WITH(options.Check(), Catch::Contains("fit.time_budget must be positive when fit.max_steps is 0"));
  options = ImageFitOptions();
  options.snapshot_steps = "10,x";
  CHECK_THROWS_WITH(options.Check(), Catch::StartsWith("fit.snapshot_steps must be positive step numbers"));
}

}  // namespace p2n::testing
