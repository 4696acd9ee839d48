// Splats in glTF with KHR_gaussian_splatting: what we write reads back to the same values (rotations normalised,
// opacities through the sigmoid and back), every degree of spherical harmonics in its own attributes, and damaged
// files are refused with their name. Khronos's validator reads the stage's file in viewer_test.cc.

#include <catch2/catch.hpp>

#include <cmath>

#include "splat/splat_gltf.h"
#include "tests/random_splats.h"

namespace p2n::testing {

TEST_CASE("splats.glb reads back to the values written, at every SH degree", "[splat]") {
  for (const int degree : {0, 1, 3}) {
    Gaussians<float> g = RandomSplats(50, 7);
    if (degree < 3) {  // the first coefficients of each splat, as a lower degree keeps them
      g.sh_degree = degree;
      const int rest = g.coefficients() - 1;
      std::vector<float> sh(3 * rest * g.size());
      for (size_t i = 0; i < g.size(); ++i) {
        for (int k = 0; k < 3 * rest; ++k) sh[3 * rest * i + k] = g.sh_rest[45 * i + k];
      }
      g.sh_rest = sh;
    }
    const std::string bytes = SplatGlbBytes(g, "test");
    const Gaussians<float> back = ParseSplatGlb(bytes, "splats.glb");
    REQUIRE(back.size() == g.size());
    REQUIRE(back.sh_degree == degree);
    CHECK(back.positions == g.positions);
    CHECK(back.log_scales == g.log_scales);
    CHECK(back.sh_dc == g.sh_dc);
    CHECK(back.sh_rest == g.sh_rest);
    for (size_t i = 0; i < g.size(); ++i) {
      CHECK(QuaternionError(&back.rotations[4 * i], &g.rotations[4 * i]) < 1e-6f);
      CHECK(back.opacity_logits[i] == Approx(g.opacity_logits[i]).margin(1e-4));
    }
    // Every coefficient of every degree named as the extension names it.
    for (int l = 0; l <= degree; ++l) {
      for (int n = 0; n <= 2 * l; ++n) {
        CHECK(bytes.find("KHR_gaussian_splatting:SH_DEGREE_" + std::to_string(l) + "_COEF_" + std::to_string(n)) !=
              std::string::npos);
      }
    }
    CHECK(bytes.find("KHR_gaussian_splatting:SH_DEGREE_" + std::to_string(degree + 1)) == std::string::npos);
  }
}

TEST_CASE("damaged splats.glb files are refused with the file's name", "[splat]") {
  const std::string bytes = SplatGlbBytes(RandomSplats(5, 3), "test");
  CHECK_THROWS_WITH(ParseSplatGlb(bytes.substr(0, bytes.size() - 40), "cut.glb"), Catch::Contains("cut.glb"));
  CHECK_THROWS_WITH(ParseSplatGlb("not glTF", "text.glb"), Catch::Contains("text.glb"));
  std::string renamed = bytes;
  for (size_t at = renamed.find("KHR_gaussian_splatting:OPACITY"); at != std::string::npos;
       at = renamed.find("KHR_gaussian_splatting:OPACITY", at + 1)) {
    renamed[at + 23] = 'X';  // ...:XPACITY, same length
  }
  CHECK_THROWS_WITH(ParseSplatGlb(renamed, "b.glb"),
                    Catch::Contains("b.glb") && Catch::Contains("KHR_gaussian_splatting:OPACITY"));
}

}  // namespace p2n::testing
