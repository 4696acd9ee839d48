// Niantic's SPZ: what we write reads back within each attribute's quantisation in the splat PLY's axes, a version 2
// file (rotations in three bytes) reads as its bytes say, and damaged files are refused with their name.
// splat-transform, an independent reader, reads the same files in viewer_test.cc.

#include <catch2/catch.hpp>

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "splat/splat_ply.h"
#include "splat/spz.h"
#include "tests/random_splats.h"
#include "tests/test_util.h"

namespace p2n::testing {
namespace {

// `raw` as one gzip stream.
std::string Gzip(const std::string& raw, const TempDir& dir) {
  const std::string path = (dir / "stream.gz").string();
  gzFile file = gzopen(path.c_str(), "wb");
  REQUIRE(file != nullptr);
  REQUIRE(gzwrite(file, raw.data(), static_cast<unsigned>(raw.size())) == static_cast<int>(raw.size()));
  REQUIRE(gzclose(file) == Z_OK);
  return ReadText(path);
}

// A 16-byte SPZ header.
std::string Header(uint32_t version, uint32_t count, uint8_t sh_degree, uint8_t fractional_bits) {
  std::string header(16, '\0');
  const uint32_t words[3] = {0x5053474e, version, count};
  std::memcpy(header.data(), words, sizeof(words));
  header[12] = static_cast<char>(sh_degree);
  header[13] = static_cast<char>(fractional_bits);
  return header;
}

}  // namespace

TEST_CASE("SPZ: our files read back within each attribute's quantisation", "[splat]") {
  const Gaussians<float> g = RandomSplats(2000, 7);
  const std::vector<char> bytes = SpzBytes(g);
  CHECK((uint8_t(bytes[0]) == 0x1f && uint8_t(bytes[1]) == 0x8b));  // gzip
  CHECK(bytes.size() < SplatPlyBytes(g).size() / 3);                // 65 bytes a splat before gzip, 248 in the PLY
  const Gaussians<float> read = ParseSpz(std::string(bytes.begin(), bytes.end()), "splats.spz");
  REQUIRE(read.size() == g.size());
  REQUIRE(read.sh_degree == 3);
  float position = 0, scale = 0, alpha = 0, colour = 0, rotation = 0, sh = 0;
  for (size_t i = 0; i < g.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      position = std::max(position, std::abs(read.positions[3 * i + a] - g.positions[3 * i + a]));
      scale = std::max(scale, std::abs(read.log_scales[3 * i + a] - g.log_scales[3 * i + a]));
      colour = std::max(colour, std::abs(read.sh_dc[3 * i + a] - g.sh_dc[3 * i + a]));
    }
    alpha = std::max(alpha, std::abs(Sigmoid(read.opacity_logits[i]) - Sigmoid(g.opacity_logits[i])));
    rotation = std::max(rotation, QuaternionError(&g.rotations[4 * i], &read.rotations[4 * i]));
    for (int k = 0; k < 45; ++k) sh = std::max(sh, std::abs(read.sh_rest[45 * i + k] - g.sh_rest[45 * i + k]));
  }
  // Positions below 2 get 20 fractional bits; scales steps of 1/16, opacity and colour of 1/255 (colour as
  // 0.15 f_dc), the rotation's three smallest components 9 bits of 1/sqrt(2); SH steps of 1/128.
  CHECK(position <= 0.5f / (1 << 20) + 1e-6f);
  CHECK(scale <= 0.5f / 16 + 1e-5f);
  CHECK(alpha <= 0.5f / 255 + 1e-5f);
  CHECK(colour <= 0.5f / 255 / 0.15f + 1e-5f);
  CHECK(rotation < 0.0015f);
  CHECK(sh <= 0.5f / 128 + 1e-6f);
}

TEST_CASE("SPZ: a version 2 file reads as its bytes say, in the splat PLY's axes", "[splat]") {
  TempDir dir;
  // One splat of SH degree 0 at SPZ's (1, 2, -0.5) with 8 fractional bits; opacity 255, colour bytes 128 + 38,
  // scales (s + 10) * 16 = 96, and a rotation by 90 degrees about SPZ's y: x y z = 0, 0.7071, 0 -> bytes
  // 127.5 (x + 1).
  std::string body;
  for (const int fixed : {256, 512, -128})
    for (int b = 0; b < 3; ++b) body.push_back(static_cast<char>((fixed >> (8 * b)) & 0xff));
  body += std::string{char(255), char(166), char(166), char(166), char(96), char(96), char(96)};
  body += std::string{char(128), char(218), char(128)};
  const Gaussians<float> g = ParseSpz(Gzip(Header(2, 1, 0, 8) + body, dir), "v2.spz");
  REQUIRE(g.size() == 1);
  CHECK(g.positions == std::vector<float>{1, -2, 0.5f});  // y and z turned
  CHECK(g.log_scales == std::vector<float>{-4, -4, -4});
  CHECK(Sigmoid(g.opacity_logits[0]) == Approx(254.5 / 255));  // 255 read as 254.5: a finite logit
  CHECK(g.sh_dc[0] == Approx((166 / 255.0 - 0.5) / 0.15));
  const float half = std::sqrt(0.5f);
  const float expected[4] = {half, 0, -half, 0};  // w x y z: about the PLY's y, turned
  CHECK(QuaternionError(expected, g.rotations.data()) < 0.01f);
}

TEST_CASE("Damaged SPZ files are refused with the file's name", "[splat]") {
  TempDir dir;
  const std::vector<char> bytes = SpzBytes(RandomSplats(50, 3));
  const std::string file(bytes.begin(), bytes.end());
  CHECK_THROWS_WITH(ParseSpz(file.substr(0, file.size() - 20), "cut.spz"),
                    Catch::Contains("cut.spz") && Catch::Contains("cut short"));
  CHECK_THROWS_WITH(ParseSpz("not an spz file", "text.spz"), Catch::Contains("text.spz: not an SPZ file"));
  CHECK_THROWS_WITH(ParseSpz(Header(4, 10, 0, 12) + std::string(100, '\0'), "v4.spz"),
                    Catch::Contains("v4.spz: SPZ version 4 is not read here"));
  CHECK_THROWS_WITH(ParseSpz(Gzip(Header(1, 1, 0, 12), dir), "v1.spz"), Catch::Contains("version 1"));
  CHECK_THROWS_WITH(ParseSpz(Gzip(Header(3, 1000, 0, 12) + std::string(500, '\0'), dir), "short.spz"),
                    Catch::Contains("short.spz: cut short (1000 splats need"));
  CHECK_THROWS_WITH(ParseSpz(Gzip(Header(3, 1, 5, 12), dir), "degree.spz"), Catch::Contains("SH degree 5"));
  CHECK_THROWS_WITH(ParseSpz(Gzip(std::string(20, 'x'), dir), "magic.spz"), Catch::Contains("no NGSP header"));
}

}  // namespace p2n::testing
