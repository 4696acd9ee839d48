#include "splat/spz.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "base/format.h"

namespace p2n {
namespace {

constexpr uint32_t kMagic = 0x5053474e;  // "NGSP"
constexpr uint32_t kVersion = 3;
constexpr int kHeaderBytes = 16;
constexpr float kColourScale = 0.15f;
constexpr int kMaxFractionalBits = 20;
constexpr int32_t kMaxFixed = (1 << 23) - 1;
// Signs of each higher SH coefficient (degree 1's three, then 2's five, 3's seven) between the PLY's axes and
// SPZ's (y and z turned): the sign of y and z in each basis function.
constexpr std::array<float, 15> kShAxisSigns = {-1, -1, 1, -1, 1, 1, -1, 1, -1, 1, -1, -1, 1, -1, 1};
constexpr std::array<float, 3> kAxisSigns = {1, -1, -1};

// The nearest byte (NaN: 0).
uint8_t ToByte(float x) { return std::isnan(x) ? 0 : static_cast<uint8_t>(std::clamp(std::round(x), 0.0f, 255.0f)); }

// The most fractional bits that keep every coordinate within 24 bits.
int FractionalBits(const std::vector<float>& positions) {
  float largest = 0;
  for (const float p : positions)
    if (std::isfinite(p)) largest = std::max(largest, std::abs(p));
  int bits = kMaxFractionalBits;
  while (bits > 0 && largest * static_cast<float>(1 << bits) > kMaxFixed) --bits;
  return bits;
}

// x y z w (SPZ's order, its axes) -> 32 bits: the largest component's index, then the other three as a sign and 9
// bits of their magnitude over 1 / sqrt(2), the quaternion negated when its largest component is negative.
uint32_t PackRotation(std::array<float, 4> q) {
  const float norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(norm > 0) || !std::isfinite(norm))
    q = {0, 0, 0, 1};
  else
    for (float& c : q) c /= norm;
  size_t largest = 0;
  for (size_t i = 1; i < 4; ++i)
    if (std::abs(q[i]) > std::abs(q[largest])) largest = i;
  const bool negate = q[largest] < 0;
  uint32_t packed = static_cast<uint32_t>(largest);
  for (size_t i = 0; i < 4; ++i) {
    if (i == largest) continue;
    const uint32_t sign = (q[i] < 0) != negate;
    const auto magnitude = static_cast<uint32_t>(std::min(511.0f * std::abs(q[i]) * float(M_SQRT2) + 0.5f, 511.0f));
    packed = (packed << 10) | (sign << 9) | magnitude;
  }
  return packed;
}

std::array<float, 4> UnpackRotation(uint32_t packed) {
  const size_t largest = packed >> 30;
  std::array<float, 4> q{};
  float sum = 0;
  for (int i = 3; i >= 0; --i) {
    if (static_cast<size_t>(i) == largest) continue;
    const float magnitude = static_cast<float>(packed & 511) / 511.0f * float(M_SQRT1_2);
    q[i] = (packed & 512) ? -magnitude : magnitude;
    sum += magnitude * magnitude;
    packed >>= 10;
  }
  q[largest] = std::sqrt(std::max(0.0f, 1.0f - sum));
  return q;
}

template <class T>
void Put(std::string* out, T value) {
  out->append(reinterpret_cast<const char*>(&value), sizeof(value));
}

std::string Gzip(const std::string& raw) {
  z_stream stream{};
  if (deflateInit2(&stream, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 15 + 16, 9, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("SPZ: cannot start gzip compression");
  std::string out(deflateBound(&stream, raw.size()), '\0');
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(raw.data()));
  stream.avail_in = static_cast<uInt>(raw.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(out.size());
  const int result = deflate(&stream, Z_FINISH);
  out.resize(stream.total_out);
  deflateEnd(&stream);
  if (result != Z_STREAM_END) throw std::runtime_error("SPZ: gzip compression failed");
  return out;
}

// The bytes of one gzip stream; the first kHeaderBytes once inflated go to `limit`, which says how many in all
// the stream may hold (more is an error, as is a damaged or cut stream), std::runtime_error naming `name`.
template <class Limit>
std::string Gunzip(const std::string& bytes, const std::string& name, Limit limit) {
  z_stream stream{};
  if (inflateInit2(&stream, 15 + 16) != Z_OK) throw std::runtime_error(name + ": cannot start gzip decompression");
  const std::unique_ptr<z_stream, int (*)(z_stream*)> end(&stream, inflateEnd);  // `limit` may throw
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  stream.avail_in = static_cast<uInt>(bytes.size());
  std::string out;
  size_t most = kHeaderBytes;
  bool limited = false;
  int result = Z_OK;
  while (result == Z_OK) {
    constexpr size_t kChunk = 1 << 16;
    const size_t before = out.size();
    out.resize(before + kChunk);
    stream.next_out = reinterpret_cast<Bytef*>(out.data() + before);
    stream.avail_out = kChunk;
    result = inflate(&stream, Z_NO_FLUSH);
    out.resize(before + kChunk - stream.avail_out);
    if (result == Z_BUF_ERROR && stream.avail_in == 0) result = Z_DATA_ERROR;  // cut short
    if (!limited && out.size() >= kHeaderBytes) most = limit(out), limited = true;
    if (limited && out.size() > most) result = Z_MEM_ERROR;
  }
  if (result == Z_MEM_ERROR) throw std::runtime_error(name + ": holds more than its header's splats");
  if (result != Z_STREAM_END)
    throw std::runtime_error(name + ": not an SPZ file (its gzip stream is damaged or cut short)");
  return out;
}

template <class T>
T Get(const std::string& bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(value));
  return value;
}

struct Header {
  uint32_t version = 0, count = 0;
  int sh_degree = 0, fractional_bits = 0;
  size_t BodyBytes() const {
    const size_t rotation = version >= 3 ? 4 : 3;
    return size_t{count} * (9 + 1 + 3 + 3 + rotation + 3 * (ShCoefficients(sh_degree) - 1));
  }
};

// The header of the inflated stream; std::runtime_error naming `name` for anything we cannot read.
Header ReadHeader(const std::string& raw, const std::string& name) {
  if (Get<uint32_t>(raw, 0) != kMagic) throw std::runtime_error(name + ": not an SPZ file (no NGSP header)");
  Header header;
  header.version = Get<uint32_t>(raw, 4);
  header.count = Get<uint32_t>(raw, 8);
  header.sh_degree = static_cast<uint8_t>(raw[12]);
  header.fractional_bits = static_cast<uint8_t>(raw[13]);
  if (header.version != 2 && header.version != 3)
    throw std::runtime_error(
        format("{}: SPZ version {} is not read here (2 and 3 are); convert it with "
               "splat-transform or Niantic's spz tools",
               name, header.version));
  if (header.sh_degree > kMaxShDegree)
    throw std::runtime_error(format("{}: SH degree {} (at most {})", name, header.sh_degree, kMaxShDegree));
  if (header.fractional_bits > 24)
    throw std::runtime_error(format("{}: {} fractional bits in 24-bit positions", name, header.fractional_bits));
  return header;
}

}  // namespace

std::vector<char> SpzBytes(const Gaussians<float>& g) {
  const size_t n = g.size();
  const int rest = g.coefficients() - 1;
  const int bits = FractionalBits(g.positions);
  std::string raw;
  Put(&raw, kMagic);
  Put(&raw, kVersion);
  Put(&raw, static_cast<uint32_t>(n));
  Put(&raw, static_cast<uint8_t>(g.sh_degree));
  Put(&raw, static_cast<uint8_t>(bits));
  Put(&raw, uint8_t{0});  // flags: not antialiased
  Put(&raw, uint8_t{0});
  for (size_t i = 0; i < 3 * n; ++i) {
    const float scaled = g.positions[i] * kAxisSigns[i % 3] * static_cast<float>(1 << bits);
    const auto fixed = static_cast<int32_t>(
        std::clamp(std::isfinite(scaled) ? std::round(scaled) : 0.0f, float(-kMaxFixed), float(kMaxFixed)));
    for (int b = 0; b < 3; ++b) raw.push_back(static_cast<char>((fixed >> (8 * b)) & 0xff));
  }
  for (size_t i = 0; i < n; ++i) raw.push_back(static_cast<char>(ToByte(Sigmoid(g.opacity_logits[i]) * 255.0f)));
  for (size_t i = 0; i < 3 * n; ++i)
    raw.push_back(static_cast<char>(ToByte(g.sh_dc[i] * (kColourScale * 255.0f) + 127.5f)));
  for (size_t i = 0; i < 3 * n; ++i) raw.push_back(static_cast<char>(ToByte((g.log_scales[i] + 10.0f) * 16.0f)));
  for (size_t i = 0; i < n; ++i) {
    const float* r = &g.rotations[4 * i];  // w x y z
    Put(&raw, PackRotation({r[1], -r[2], -r[3], r[0]}));
  }
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < rest; ++k) {
      for (int c = 0; c < 3; ++c)
        raw.push_back(static_cast<char>(ToByte(128.0f + 128.0f * g.sh_rest[(i * rest + k) * 3 + c] * kShAxisSigns[k])));
    }
  }
  const std::string compressed = Gzip(raw);
  return std::vector<char>(compressed.begin(), compressed.end());
}

Gaussians<float> ParseSpz(const std::string& bytes, const std::string& name) {
  if (bytes.size() >= kHeaderBytes && Get<uint32_t>(bytes, 0) == kMagic)  // version 4 on: a plain header, zstd
    ReadHeader(bytes, name);
  const std::string raw = Gunzip(bytes, name, [&](const std::string& head) {
    return kHeaderBytes + ReadHeader(head, name).BodyBytes() + (1 << 20);  // room for extensions, unread
  });
  if (raw.size() < kHeaderBytes) throw std::runtime_error(name + ": not an SPZ file (shorter than its header)");
  const Header header = ReadHeader(raw, name);
  if (raw.size() < kHeaderBytes + header.BodyBytes())
    throw std::runtime_error(format("{}: cut short ({} splats need {} bytes, it holds {})", name, header.count,
                                    header.BodyBytes(), raw.size() - kHeaderBytes));
  Gaussians<float> g;
  g.sh_degree = header.sh_degree;
  g.Resize(header.count);
  const size_t n = header.count;
  const int rest = g.coefficients() - 1;
  const auto* at = reinterpret_cast<const uint8_t*>(raw.data()) + kHeaderBytes;
  const float unit = 1.0f / static_cast<float>(1 << header.fractional_bits);
  for (size_t i = 0; i < 3 * n; ++i, at += 3) {
    const int32_t fixed =
        static_cast<int32_t>(uint32_t{at[0]} << 8 | uint32_t{at[1]} << 16 | uint32_t{at[2]} << 24) >> 8;
    g.positions[i] = static_cast<float>(fixed) * unit * kAxisSigns[i % 3];
  }
  for (size_t i = 0; i < n; ++i) g.opacity_logits[i] = Logit(std::clamp(*at++ / 255.0f, 0.5f / 255, 254.5f / 255));
  for (size_t i = 0; i < 3 * n; ++i) g.sh_dc[i] = (*at++ / 255.0f - 0.5f) / kColourScale;
  for (size_t i = 0; i < 3 * n; ++i) g.log_scales[i] = *at++ / 16.0f - 10.0f;
  for (size_t i = 0; i < n; ++i) {
    std::array<float, 4> q;  // x y z w
    if (header.version >= 3) {
      q = UnpackRotation(uint32_t{at[0]} | uint32_t{at[1]} << 8 | uint32_t{at[2]} << 16 | uint32_t{at[3]} << 24);
      at += 4;
    } else {
      float sum = 0;
      for (int c = 0; c < 3; ++c) q[c] = *at++ / 127.5f - 1.0f, sum += q[c] * q[c];
      q[3] = std::sqrt(std::max(0.0f, 1.0f - sum));
    }
    float* r = &g.rotations[4 * i];
    r[0] = q[3], r[1] = q[0], r[2] = -q[1], r[3] = -q[2];
  }
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < rest; ++k) {
      for (int c = 0; c < 3; ++c) g.sh_rest[(i * rest + k) * 3 + c] = (*at++ - 128.0f) / 128.0f * kShAxisSigns[k];
    }
  }
  return g;
}

}  // namespace p2n
