#include "splat/rasterizer.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace p2n {
namespace {

constexpr double kMaxAlpha = 0.99;
constexpr double kMinAlpha = 1.0 / 255.0;
constexpr double kMinTransmittance = 1e-4;

// The Gaussian's weight exponent at pixel centre (px, py): -½ dᵀ Σ₂⁻¹ d with d = mean - pixel.
template <typename T>
T Power(const Splat2D<T>& s, T px, T py, T* dx, T* dy) {
  *dx = s.x - px;
  *dy = s.y - py;
  return T(-0.5) * (s.conic_a * *dx * *dx + s.conic_c * *dy * *dy) - s.conic_b * *dx * *dy;
}

}  // namespace

template <typename T>
void Rasterizer<T>::Forward(const Gaussians<T>& gaussians, const PinholeCamera& camera, const RasterOptions& options) {
  gaussians_ = &gaussians;
  options_ = options;
  camera_ = SplatCamera<T>::From(camera);
  tiles_x_ = (camera.width + kSplatTileSize - 1) / kSplatTileSize;
  tiles_y_ = (camera.height + kSplatTileSize - 1) / kSplatTileSize;
  Project();
  BinAndSort();
  Blend();
}

template <typename T>
void Rasterizer<T>::Project() {
  const size_t n = gaussians_->size();
  splats_.resize(n);
  depths_.resize(n);
  rects_.assign(n, Rect{});
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) {
      T radius = 0;
      if (!ProjectGaussian(*gaussians_, i, camera_, options_.projection, &splats_[i], &depths_[i], &radius)) continue;
      const auto tile = [](T v) { return static_cast<int>(std::floor(v / kSplatTileSize)); };
      const T x = splats_[i].x, y = splats_[i].y;
      Rect r;
      // Clamp in T before converting: a huge or far Gaussian must not overflow int.
      r.x0 = tile(std::clamp(x - radius, T(0), T(camera_.width)));
      r.y0 = tile(std::clamp(y - radius, T(0), T(camera_.height)));
      r.x1 = std::min(tiles_x_, tile(std::clamp(x + radius, T(-1), T(camera_.width))) + 1);
      r.y1 = std::min(tiles_y_, tile(std::clamp(y + radius, T(-1), T(camera_.height))) + 1);
      if (r.x0 < r.x1 && r.y0 < r.y1) rects_[i] = r;
    }
  });
}

template <typename T>
void Rasterizer<T>::BinAndSort() {
  const size_t tiles = static_cast<size_t>(tiles_x_) * tiles_y_;
  tile_begin_.assign(tiles + 1, 0);
  drawn_ = 0;
  for (const Rect& r : rects_) {
    if (r.x0 >= r.x1) continue;
    ++drawn_;
    for (int ty = r.y0; ty < r.y1; ++ty) {
      for (int tx = r.x0; tx < r.x1; ++tx) ++tile_begin_[ty * tiles_x_ + tx + 1];
    }
  }
  for (size_t t = 0; t < tiles; ++t) tile_begin_[t + 1] += tile_begin_[t];
  entries_.resize(tile_begin_[tiles]);
  std::vector<size_t> next(tile_begin_.begin(), tile_begin_.end() - 1);
  for (size_t i = 0; i < rects_.size(); ++i) {
    const Rect& r = rects_[i];
    for (int ty = r.y0; ty < r.y1; ++ty) {
      for (int tx = r.x0; tx < r.x1; ++tx) entries_[next[ty * tiles_x_ + tx]++] = static_cast<uint32_t>(i);
    }
  }
  tbb::parallel_for(size_t(0), tiles, [&](size_t t) {
    std::sort(entries_.begin() + tile_begin_[t], entries_.begin() + tile_begin_[t + 1],
              [&](uint32_t a, uint32_t b) { return depths_[a] < depths_[b] || (depths_[a] == depths_[b] && a < b); });
  });
}

template <typename T>
void Rasterizer<T>::Blend() {
  const int width = camera_.width, height = camera_.height;
  rgb_.assign(static_cast<size_t>(width) * height * 3, T(0));
  transmittance_.assign(static_cast<size_t>(width) * height, T(1));
  contributors_.assign(static_cast<size_t>(width) * height, 0);
  const T background[3] = {T(options_.background[0]), T(options_.background[1]), T(options_.background[2])};
  tbb::parallel_for(0, tiles_x_ * tiles_y_, [&](int tile) {
    const int tx = tile % tiles_x_, ty = tile / tiles_x_;
    const size_t begin = tile_begin_[tile], end = tile_begin_[tile + 1];
    for (int y = ty * kSplatTileSize; y < std::min(height, (ty + 1) * kSplatTileSize); ++y) {
      for (int x = tx * kSplatTileSize; x < std::min(width, (tx + 1) * kSplatTileSize); ++x) {
        const T px = T(x) + T(0.5), py = T(y) + T(0.5);
        T transmittance = 1, colour[3] = {0, 0, 0};
        uint32_t contributors = 0;
        for (size_t e = begin; e < end; ++e) {
          const Splat2D<T>& s = splats_[entries_[e]];
          T dx, dy;
          const T power = Power(s, px, py, &dx, &dy);
          if (power > 0) continue;
          const T alpha = std::min(T(kMaxAlpha), s.opacity * std::exp(power));
          if (alpha < T(kMinAlpha)) continue;
          const T next = transmittance * (1 - alpha);
          if (next < T(kMinTransmittance)) break;
          for (int c = 0; c < 3; ++c) colour[c] += s.rgb[c] * alpha * transmittance;
          transmittance = next;
          contributors = static_cast<uint32_t>(e - begin + 1);
        }
        const size_t pixel = static_cast<size_t>(y) * width + x;
        for (int c = 0; c < 3; ++c) rgb_[3 * pixel + c] = colour[c] + transmittance * background[c];
        transmittance_[pixel] = transmittance;
        contributors_[pixel] = contributors;
      }
    }
  });
}

template <typename T>
void Rasterizer<T>::Backward(const std::vector<T>& d_rgb, Gaussians<T>* grads, std::vector<T>* screen_grads) const {
  const int width = camera_.width, height = camera_.height;
  const size_t n = gaussians_->size();
  tbb::enumerable_thread_specific<std::vector<Splat2D<T>>> local([n] { return std::vector<Splat2D<T>>(n); });
  const T background[3] = {T(options_.background[0]), T(options_.background[1]), T(options_.background[2])};
  tbb::parallel_for(0, tiles_x_ * tiles_y_, [&](int tile) {
    std::vector<Splat2D<T>>& splat_grads = local.local();
    const int tx = tile % tiles_x_, ty = tile / tiles_x_;
    const size_t begin = tile_begin_[tile];
    for (int y = ty * kSplatTileSize; y < std::min(height, (ty + 1) * kSplatTileSize); ++y) {
      for (int x = tx * kSplatTileSize; x < std::min(width, (tx + 1) * kSplatTileSize); ++x) {
        const size_t pixel = static_cast<size_t>(y) * width + x;
        const T px = T(x) + T(0.5), py = T(y) + T(0.5);
        const T* g = &d_rgb[3 * pixel];
        const T final_transmittance = transmittance_[pixel];
        const T background_dot = background[0] * g[0] + background[1] * g[1] + background[2] * g[2];
        T transmittance = final_transmittance, behind[3] = {0, 0, 0}, last_alpha = 0, last_rgb[3] = {0, 0, 0};
        for (size_t e = begin + contributors_[pixel]; e-- > begin;) {
          const Splat2D<T>& s = splats_[entries_[e]];
          T dx, dy;
          const T power = Power(s, px, py, &dx, &dy);
          if (power > 0) continue;
          const T weight = std::exp(power);
          const T raw_alpha = s.opacity * weight;
          const T alpha = std::min(T(kMaxAlpha), raw_alpha);
          if (alpha < T(kMinAlpha)) continue;
          transmittance /= 1 - alpha;
          Splat2D<T>& out = splat_grads[entries_[e]];
          // behind: the colour of what lies behind this Gaussian, as seen through it.
          T d_alpha = 0;
          for (int c = 0; c < 3; ++c) {
            behind[c] = last_alpha * last_rgb[c] + (1 - last_alpha) * behind[c];
            last_rgb[c] = s.rgb[c];
            d_alpha += (s.rgb[c] - behind[c]) * g[c];
            out.rgb[c] += alpha * transmittance * g[c];
          }
          d_alpha = d_alpha * transmittance - final_transmittance / (1 - alpha) * background_dot;
          last_alpha = alpha;
          if (raw_alpha >= T(kMaxAlpha)) continue;  // clamped: no gradient to opacity or shape
          out.opacity += weight * d_alpha;
          const T d_power = d_alpha * alpha;
          out.x += d_power * -(s.conic_a * dx + s.conic_b * dy);
          out.y += d_power * -(s.conic_c * dy + s.conic_b * dx);
          out.conic_a += d_power * T(-0.5) * dx * dx;
          out.conic_b += d_power * -dx * dy;
          out.conic_c += d_power * T(-0.5) * dy * dy;
        }
      }
    }
  });
  if (screen_grads) screen_grads->resize(2 * n, T(0));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) {
      if (rects_[i].x0 >= rects_[i].x1) continue;
      Splat2D<T> sum;
      for (const auto& buffer : local) {
        const Splat2D<T>& b = buffer[i];
        sum.x += b.x, sum.y += b.y, sum.conic_a += b.conic_a, sum.conic_b += b.conic_b, sum.conic_c += b.conic_c;
        sum.opacity += b.opacity;
        for (int c = 0; c < 3; ++c) sum.rgb[c] += b.rgb[c];
      }
      ProjectGaussianBackward(*gaussians_, i, camera_, options_.projection, sum, grads);
      if (screen_grads) (*screen_grads)[2 * i] += sum.x, (*screen_grads)[2 * i + 1] += sum.y;
    }
  });
}

template class Rasterizer<float>;
template class Rasterizer<double>;

}  // namespace p2n
