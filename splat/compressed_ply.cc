#include "splat/compressed_ply.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <string>

#include <Eigen/Core>

#include "base/ply.h"

namespace p2n {
namespace {

constexpr float kMaxLogScale = 20;  // beyond it a chunk's bounds would lose every other splat's precision

// Gaussian indices in the order of a 30-bit Morton code of their positions in the bounding box.
std::vector<size_t> MortonOrder(const Gaussians<float>& g) {
  Eigen::Array3f lo = Eigen::Array3f::Constant(INFINITY), hi = -lo;
  for (size_t i = 0; i < g.size(); ++i) {
    const Eigen::Array3f p(g.positions[3 * i], g.positions[3 * i + 1], g.positions[3 * i + 2]);
    if (p.allFinite()) lo = lo.min(p), hi = hi.max(p);
  }
  const auto spread = [](uint32_t v) {  // 10 bits to every third of 30
    v = (v | (v << 16)) & 0x030000FF;
    v = (v | (v << 8)) & 0x0300F00F;
    v = (v | (v << 4)) & 0x030C30C3;
    return (v | (v << 2)) & 0x09249249;
  };
  std::vector<uint32_t> codes(g.size());
  for (size_t i = 0; i < g.size(); ++i) {
    uint32_t code = 0;
    for (int a = 0; a < 3; ++a) {
      const float t = (g.positions[3 * i + a] - lo[a]) / std::max(hi[a] - lo[a], 1e-20f);
      code |= spread(static_cast<uint32_t>(std::clamp(std::isfinite(t) ? t : 0.f, 0.f, 1.f) * 1023)) << a;
    }
    codes[i] = code;
  }
  std::vector<size_t> order(g.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return codes[a] < codes[b]; });
  return order;
}

// The fraction of [lo, hi] that v is at, in `bits` bits.
uint32_t Quantize(float v, float lo, float hi, int bits) {
  const float t = hi - lo > 1e-5f ? (v - lo) / (hi - lo) : 0;
  const uint32_t top = (1u << bits) - 1;
  return static_cast<uint32_t>(std::clamp(std::floor(std::clamp(t, 0.f, 1.f) * top + 0.5f), 0.f, float(top)));
}

// The three smallest components of the unit quaternion q (w, x, y, z), the largest made positive, in 10 bits
// each over [-1/sqrt(2), 1/sqrt(2)]; the top 2 bits name the largest.
uint32_t PackRotation(const float* q) {
  float v[4] = {q[0], q[1], q[2], q[3]};
  const float norm = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
  if (!(norm > 0) || !std::isfinite(norm))
    v[0] = 1, v[1] = v[2] = v[3] = 0;
  else
    for (float& c : v) c /= norm;
  int largest = 0;
  for (int i = 1; i < 4; ++i)
    if (std::abs(v[i]) > std::abs(v[largest])) largest = i;
  const float sign = v[largest] < 0 ? -1.f : 1.f;
  uint32_t packed = largest;
  for (int i = 0; i < 4; ++i) {
    if (i != largest) packed = (packed << 10) | Quantize(sign * v[i] * float(M_SQRT1_2) + 0.5f, 0, 1, 10);
  }
  return packed;
}

uint32_t Pack111011(const float* v, const float* lo, const float* hi) {
  return Quantize(v[0], lo[0], hi[0], 11) << 21 | Quantize(v[1], lo[1], hi[1], 10) << 11 |
         Quantize(v[2], lo[2], hi[2], 11);
}

template <class T>
void Put(std::vector<char>* bytes, const T& value) {
  const char* p = reinterpret_cast<const char*>(&value);
  bytes->insert(bytes->end(), p, p + sizeof(T));
}

// One chunk's 18 bounds and its splats' four packed words.
void WriteChunk(const Gaussians<float>& g, const size_t* index, size_t count, std::vector<char>* chunks,
                std::vector<char>* vertices) {
  float lo[9], hi[9];  // position, log-scale, base colour
  std::fill(lo, lo + 9, INFINITY);
  std::fill(hi, hi + 9, -INFINITY);
  std::vector<float> values(count * 9);
  for (size_t j = 0; j < count; ++j) {
    const size_t i = index[j];
    float* v = &values[9 * j];
    for (int a = 0; a < 3; ++a) {
      v[a] = std::isfinite(g.positions[3 * i + a]) ? g.positions[3 * i + a] : 0;
      v[3 + a] = std::clamp(g.log_scales[3 * i + a], -kMaxLogScale, kMaxLogScale);
      v[6 + a] = g.sh_dc[3 * i + a] * float(kShC0) + 0.5f;
    }
    for (int k = 0; k < 9; ++k) {
      if (!std::isfinite(v[k])) v[k] = 0;
      lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
    }
  }
  for (int part = 0; part < 3; ++part) {  // min_x..z, max_x..z, min_scale.., max_scale.., min_r.., max_r..
    for (int a = 0; a < 3; ++a) Put(chunks, lo[3 * part + a]);
    for (int a = 0; a < 3; ++a) Put(chunks, hi[3 * part + a]);
  }
  for (size_t j = 0; j < count; ++j) {
    const size_t i = index[j];
    const float* v = &values[9 * j];
    const float alpha = 1 / (1 + std::exp(-g.opacity_logits[i]));
    uint32_t colour = 0;
    for (int c = 0; c < 3; ++c) colour = colour << 8 | Quantize(v[6 + c], lo[6 + c], hi[6 + c], 8);
    colour = colour << 8 | Quantize(std::isfinite(alpha) ? alpha : 0, 0, 1, 8);
    Put(vertices, Pack111011(v, lo, hi));
    Put(vertices, PackRotation(&g.rotations[4 * i]));
    Put(vertices, Pack111011(v + 3, lo + 3, hi + 3));
    Put(vertices, colour);
  }
}

}  // namespace

std::vector<char> CompressedSplatPlyBytes(const Gaussians<float>& g) {
  const size_t n = g.size(), chunk_count = (n + kCompressedChunkSize - 1) / kCompressedChunkSize;
  const int rest = 3 * (g.coefficients() - 1);
  std::vector<std::string> bounds;
  for (const char* part : {"", "scale_"}) {
    for (const char* bound : {"min_", "max_"}) {
      for (const char* axis : {"x", "y", "z"}) bounds.push_back(std::string(bound) + part + axis);
    }
  }
  for (const char* bound : {"min_", "max_"}) {
    for (const char* channel : {"r", "g", "b"}) bounds.push_back(std::string(bound) + channel);
  }
  std::vector<PlyElement> elements = {
      {"chunk", chunk_count, PlyProperties("float", bounds)},
      {"vertex", n, PlyProperties("uint", {"packed_position", "packed_rotation", "packed_scale", "packed_color"})}};
  std::vector<std::string> rest_names;
  for (int k = 0; k < rest; ++k) rest_names.push_back("f_rest_" + std::to_string(k));
  if (rest > 0) elements.push_back({"sh", n, PlyProperties("uchar", rest_names)});
  const std::string header = PlyHeader(elements);

  const std::vector<size_t> order = MortonOrder(g);
  std::vector<char> bytes(header.begin(), header.end()), vertices, sh;
  for (size_t c = 0; c < chunk_count; ++c) {
    const size_t first = c * kCompressedChunkSize;
    WriteChunk(g, &order[first], std::min<size_t>(kCompressedChunkSize, n - first), &bytes, &vertices);
  }
  sh.reserve(n * rest);
  for (const size_t i : order) {
    const float* coefficients = g.sh_rest.data() + i * rest;  // none at degree 0
    for (int c = 0; c < 3; ++c) {  // f_rest order: all of red's coefficients, then green's, then blue's
      for (int k = 0; k < rest / 3; ++k) {
        const float t = coefficients[3 * k + c] / 8 + 0.5f;
        const float byte = std::clamp(std::isfinite(t) ? std::floor(t * 256) : 128.f, 0.f, 255.f);
        sh.push_back(static_cast<char>(static_cast<uint8_t>(byte)));  // a float above 127 is no char
      }
    }
  }
  bytes.insert(bytes.end(), vertices.begin(), vertices.end());
  bytes.insert(bytes.end(), sh.begin(), sh.end());
  return bytes;
}

}  // namespace p2n
