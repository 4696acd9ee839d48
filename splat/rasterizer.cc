#include "splat/rasterizer.h"

#include "splat/lanes.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>
#include <type_traits>

namespace p2n {
namespace {

constexpr double kMaxAlpha = 0.99;
constexpr double kMinAlpha = 1.0 / 255.0;
constexpr double kMinTransmittance = 1e-4;
using lanes::kLanes;  // a strip of a tile's row of pixels is blended at once, one lane per pixel
static_assert(kSplatTileSize % kLanes == 0);
constexpr int kStrips = kSplatTileSize / kLanes;  // strips a tile row
template <typename T>
using V = lanes::V<T>;
template <typename T>
using M = lanes::M<T>;
template <typename T>
using Lane = std::remove_reference_t<decltype(M<T>{}[0])>;  // a mask lane's integer type

// A tile's splats, front to back: its part of the copy the forward makes (Rasterizer::tile_splats_).
template <typename T>
using TileSplats = std::span<const TileSplat<T>>;

// The half width and height (pixels) of the box outside which splat `s` is never blended; false when it is
// blended nowhere. Footprint blends a pixel only where opacity e^(-m^2 / 2) >= kMinAlpha, m being the pixel's
// Mahalanobis distance, so within the ellipse m^2 <= 2 ln(opacity / kMinAlpha), whose box has half sides
// sqrt(m^2 sxx) and sqrt(m^2 syy) (s = the conic's inverse, the 2D covariance); the bound has 1% to spare against
// rounding. A faint or thin splat skips the tiles its 3-sigma square would have given it, and the rows and strips
// of a tile outside the box, and draws nothing different.
template <typename T>
bool DrawnExtent(const Splat2D<T>& s, T* half_x, T* half_y) {
  const T m2 = T(2.02) * std::log(s.opacity / T(kMinAlpha));
  if (!(m2 > 0)) return false;
  const T det = s.conic_a * s.conic_c - s.conic_b * s.conic_b;  // > 0: the covariance's inverse
  *half_x = std::sqrt(m2 * s.conic_c / det);
  *half_y = std::sqrt(m2 * s.conic_a / det);
  return true;
}

// A splat's offset, weight and alpha at the pixel centres (px[lane], py); the lanes where it is blended (before
// the transmittance test).
template <typename T>
struct Footprint {
  V<T> dx, dy, weight, raw_alpha, alpha;
  M<T> drawn;

  Footprint(const Splat2D<T>& s, V<T> px, T py) {
    dx = s.x - px;
    dy = lanes::Splat(s.y - py);
    const V<T> power = T(-0.5) * (s.conic_a * dx * dx + s.conic_c * dy * dy) - s.conic_b * dx * dy;
    weight = lanes::ExpNonPositive<T>(lanes::Min<T>(power, V<T>{}));
    raw_alpha = s.opacity * weight;
    alpha = lanes::Min<T>(raw_alpha, lanes::Splat(T(kMaxAlpha)));
    drawn = (power <= 0) & (alpha >= T(kMinAlpha));
  }
};

// A strip's blend, front to back.
template <typename T>
struct RowForward {
  V<T> transmittance, red, green, blue, depth;
  M<T> active;  // until the lane's transmittance would fall below the threshold (never beyond the image)
  M<T> count;   // splats up to and including the last blended
};

// Blends the tile's splats front to back into the strip of pixels (x0 + lane, py), the first `lanes` of them.
template <typename T>
void BlendRow(TileSplats<T> splats, T x0, T py, int lanes, RowForward<T>* row) {
  const V<T> px = x0 + lanes::Iota<T>();
  row->transmittance = lanes::Splat(T(1));
  row->red = row->green = row->blue = row->depth = V<T>{};
  row->active = lanes::Iota<T>() < T(lanes);
  row->count = M<T>{};
  const T x_last = x0 + T(kLanes - 1);
  for (size_t e = 0; e < splats.size(); ++e) {
    if (!splats[e].Reaches(x0, x_last, py)) continue;
    const Splat2D<T>& s = splats[e].s;
    const Footprint<T> f(s, px, py);
    const M<T> valid = f.drawn & row->active;
    const V<T> next = row->transmittance * (1 - f.alpha);
    const M<T> stop = valid & (next < T(kMinTransmittance));
    const M<T> use = valid & ~stop;
    const V<T> w = lanes::Select<T>(use, f.alpha * row->transmittance, V<T>{});
    row->red += w * s.rgb[0];
    row->green += w * s.rgb[1];
    row->blue += w * s.rgb[2];
    row->depth += w * s.depth;
    row->transmittance = lanes::Select<T>(use, next, row->transmittance);
    row->count = use ? M<T>{} + static_cast<Lane<T>>(e + 1) : row->count;
    row->active &= ~stop;
    if (!lanes::Any<T>(row->active)) break;
  }
}

// The rows [*first, *end) of a tile (its first pixel row y0, `rows` rows) within which `t` can be blended: those
// whose centre lies in its box, and one either side against rounding (Reaches decides those).
template <typename T>
void BoxRows(const TileSplat<T>& t, int y0, int rows, int* first, int* end) {
  const T top = std::floor(t.box[2] - T(y0) - T(0.5)), bottom = std::ceil(t.box[3] - T(y0) - T(0.5));
  *first = static_cast<int>(std::clamp(top, T(0), T(rows)));
  *end = static_cast<int>(std::clamp(bottom + 1, T(0), T(rows)));
}

// A strip's backward pass: each lane walks its splats back to front from its last contributor.
template <typename T>
struct RowBackward {
  V<T> transmittance, final_transmittance, background_dot;
  V<T> g_red, g_green, g_blue;  // the loss's gradient at the lane's pixel
  V<T> behind_red{}, behind_green{}, behind_blue{};
  V<T> last_alpha{}, last_red{}, last_green{}, last_blue{};
  M<T> count;
};

// A splat's gradient per lane, summed over a tile's rows.
template <typename T>
struct LaneGradient {
  V<T> x{}, y{}, conic_a{}, conic_b{}, conic_c{}, opacity{}, red{}, green{}, blue{};

  // The sum over lanes.
  Splat2D<T> Sum() const {
    Splat2D<T> out;
    out.x = lanes::Sum<T>(x), out.y = lanes::Sum<T>(y);
    out.conic_a = lanes::Sum<T>(conic_a), out.conic_b = lanes::Sum<T>(conic_b), out.conic_c = lanes::Sum<T>(conic_c);
    out.opacity = lanes::Sum<T>(opacity);
    out.rgb[0] = lanes::Sum<T>(red), out.rgb[1] = lanes::Sum<T>(green), out.rgb[2] = lanes::Sum<T>(blue);
    return out;
  }
};

// Adds to `g` the gradient of splat `s` (the tile's e-th) at the row's lanes, advancing each lane's state past it.
template <typename T>
void BackwardSplat(const Splat2D<T>& s, size_t e, V<T> px, T py, RowBackward<T>* row, LaneGradient<T>* g) {
  const Footprint<T> f(s, px, py);
  const M<T> valid = f.drawn & (static_cast<Lane<T>>(e) < row->count);
  if (!lanes::Any<T>(valid)) return;  // blended at none of the lanes: it changes neither their state nor its gradient
  const V<T> inverse = 1 / (1 - f.alpha);  // one division, used twice
  const V<T> transmittance = lanes::Select<T>(valid, row->transmittance * inverse, row->transmittance);
  row->transmittance = transmittance;
  const V<T> la = row->last_alpha;
  const V<T> br = la * row->last_red + (1 - la) * row->behind_red;
  const V<T> bg = la * row->last_green + (1 - la) * row->behind_green;
  const V<T> bb = la * row->last_blue + (1 - la) * row->behind_blue;
  V<T> d_alpha = (s.rgb[0] - br) * row->g_red + (s.rgb[1] - bg) * row->g_green + (s.rgb[2] - bb) * row->g_blue;
  d_alpha = d_alpha * transmittance - row->final_transmittance * inverse * row->background_dot;
  row->behind_red = lanes::Select<T>(valid, br, row->behind_red);
  row->behind_green = lanes::Select<T>(valid, bg, row->behind_green);
  row->behind_blue = lanes::Select<T>(valid, bb, row->behind_blue);
  row->last_red = lanes::Select<T>(valid, lanes::Splat(s.rgb[0]), row->last_red);
  row->last_green = lanes::Select<T>(valid, lanes::Splat(s.rgb[1]), row->last_green);
  row->last_blue = lanes::Select<T>(valid, lanes::Splat(s.rgb[2]), row->last_blue);
  row->last_alpha = lanes::Select<T>(valid, f.alpha, la);
  const V<T> w = lanes::Select<T>(valid, f.alpha * transmittance, V<T>{});
  // A clamped alpha passes no gradient to the opacity or the shape.
  const M<T> unclamped = valid & (f.raw_alpha < T(kMaxAlpha));
  const V<T> d_opacity = lanes::Select<T>(unclamped, f.weight * d_alpha, V<T>{});
  const V<T> d_power = lanes::Select<T>(unclamped, d_alpha * f.alpha, V<T>{});
  g->x -= d_power * (s.conic_a * f.dx + s.conic_b * f.dy);
  g->y -= d_power * (s.conic_c * f.dy + s.conic_b * f.dx);
  g->conic_a -= d_power * T(0.5) * f.dx * f.dx;
  g->conic_b -= d_power * f.dx * f.dy;
  g->conic_c -= d_power * T(0.5) * f.dy * f.dy;
  g->opacity += d_opacity;
  g->red += w * row->g_red;
  g->green += w * row->g_green;
  g->blue += w * row->g_blue;
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
  rects_.assign(n, Rect{});
  blended_.assign(n, Rect{});
  boxes_.resize(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) {
      T depth = 0, radius = 0;
      if (!ProjectGaussian(*gaussians_, i, camera_, options_.projection, &splats_[i], &depth, &radius)) continue;
      rects_[i] = TileRect(splats_[i], radius, radius);
      T half_x = 0, half_y = 0;
      if (!rects_[i].Empty() && DrawnExtent(splats_[i], &half_x, &half_y)) {
        const Splat2D<T>& s = splats_[i];
        boxes_[i] = {s.x - half_x, s.x + half_x, s.y - half_y, s.y + half_y};
        blended_[i] = TileRect(splats_[i], std::min(radius, half_x), std::min(radius, half_y));
      }
    }
  });
}

// The tiles under the box of half sides half_x, half_y about the splat's centre; empty outside the image.
template <typename T>
typename Rasterizer<T>::Rect Rasterizer<T>::TileRect(const Splat2D<T>& s, T half_x, T half_y) const {
  const auto tile = [](T v) { return static_cast<int>(std::floor(v / kSplatTileSize)); };
  Rect r;
  // Clamp in T before converting: a huge or far Gaussian must not overflow int.
  r.x0 = tile(std::clamp(s.x - half_x, T(0), T(camera_.width)));
  r.y0 = tile(std::clamp(s.y - half_y, T(0), T(camera_.height)));
  r.x1 = std::min(tiles_x_, tile(std::clamp(s.x + half_x, T(-1), T(camera_.width))) + 1);
  r.y1 = std::min(tiles_y_, tile(std::clamp(s.y + half_y, T(-1), T(camera_.height))) + 1);
  return r.Empty() ? Rect{} : r;
}

template <typename T>
void Rasterizer<T>::BinAndSort() {
  const size_t tiles = static_cast<size_t>(tiles_x_) * tiles_y_;
  tile_begin_.assign(tiles + 1, 0);
  drawn_ = std::count_if(rects_.begin(), rects_.end(), [](const Rect& r) { return !r.Empty(); });
  for (const Rect& r : blended_) {
    for (int ty = r.y0; ty < r.y1; ++ty) {
      for (int tx = r.x0; tx < r.x1; ++tx) ++tile_begin_[ty * tiles_x_ + tx + 1];
    }
  }
  for (size_t t = 0; t < tiles; ++t) tile_begin_[t + 1] += tile_begin_[t];
  entries_.resize(tile_begin_[tiles]);
  std::vector<size_t> next(tile_begin_.begin(), tile_begin_.end() - 1);
  for (size_t i = 0; i < blended_.size(); ++i) {
    const Rect& r = blended_[i];
    for (int ty = r.y0; ty < r.y1; ++ty) {
      for (int tx = r.x0; tx < r.x1; ++tx) entries_[next[ty * tiles_x_ + tx]++] = static_cast<uint32_t>(i);
    }
  }
  tbb::parallel_for(size_t(0), tiles, [&](size_t t) {
    std::sort(entries_.begin() + tile_begin_[t], entries_.begin() + tile_begin_[t + 1], [&](uint32_t a, uint32_t b) {
      const T da = splats_[a].depth, db = splats_[b].depth;
      return da < db || (da == db && a < b);
    });
  });
}

// Lists each splat's entries in the tile lists in the order of its tiles (row by row) in slots_, the splat's from
// slot_begin_[i]. A splat's tiles are its blended_ rectangle, so its k-th tile's slot is known without a search,
// and each slot is written once.
template <typename T>
void Rasterizer<T>::ListEntriesBySplat() const {
  slot_begin_.assign(blended_.size() + 1, 0);
  for (size_t i = 0; i < blended_.size(); ++i) {
    const Rect& r = blended_[i];
    slot_begin_[i + 1] = slot_begin_[i] + size_t(r.x1 - r.x0) * (r.y1 - r.y0);
  }
  slots_.resize(entries_.size());
  tbb::parallel_for(0, tiles_x_ * tiles_y_, [&](int tile) {
    const int tx = tile % tiles_x_, ty = tile / tiles_x_;
    for (size_t p = tile_begin_[tile]; p < tile_begin_[tile + 1]; ++p) {
      const Rect& r = blended_[entries_[p]];
      slots_[slot_begin_[entries_[p]] + size_t(ty - r.y0) * (r.x1 - r.x0) + (tx - r.x0)] = static_cast<uint32_t>(p);
    }
  });
}

template <typename T>
void Rasterizer<T>::Blend() {
  const int width = camera_.width, height = camera_.height;
  rgb_.resize(static_cast<size_t>(width) * height * 3);
  transmittance_.resize(static_cast<size_t>(width) * height);
  depth_.resize(static_cast<size_t>(width) * height);
  contributors_.resize(static_cast<size_t>(width) * height);
  const T background[3] = {T(options_.background[0]), T(options_.background[1]), T(options_.background[2])};
  tile_splats_.resize(entries_.size());
  tbb::parallel_for(0, tiles_x_ * tiles_y_, [&](int tile) {
    const int tx = tile % tiles_x_, ty = tile / tiles_x_, x0 = tx * kSplatTileSize;
    const size_t begin = tile_begin_[tile], end = tile_begin_[tile + 1];
    for (size_t e = begin; e < end; ++e) tile_splats_[e] = {splats_[entries_[e]], boxes_[entries_[e]]};
    const TileSplats<T> splats(tile_splats_.data() + begin, end - begin);
    RowForward<T> row;
    for (int y = ty * kSplatTileSize; y < std::min(height, (ty + 1) * kSplatTileSize); ++y) {
      for (int xs = x0; xs < std::min(width, x0 + kSplatTileSize); xs += kLanes) {
        const int lanes = std::min(kLanes, width - xs);
        BlendRow(splats, T(xs) + T(0.5), T(y) + T(0.5), lanes, &row);
        for (int l = 0; l < lanes; ++l) {
          const size_t pixel = static_cast<size_t>(y) * width + xs + l;
          const T t = row.transmittance[l];
          rgb_[3 * pixel] = row.red[l] + t * background[0];
          rgb_[3 * pixel + 1] = row.green[l] + t * background[1];
          rgb_[3 * pixel + 2] = row.blue[l] + t * background[2];
          transmittance_[pixel] = t;
          depth_[pixel] = row.depth[l];
          contributors_[pixel] = static_cast<uint32_t>(row.count[l]);
        }
      }
    }
  });
}

template <typename T>
void Rasterizer<T>::Backward(const std::vector<T>& d_rgb, Gaussians<T>* grads, std::vector<T>* screen_grads) const {
  const int width = camera_.width, height = camera_.height;
  const size_t n = gaussians_->size();
  entry_grads_.resize(entries_.size());
  const T background[3] = {T(options_.background[0]), T(options_.background[1]), T(options_.background[2])};
  tbb::parallel_for(0, tiles_x_ * tiles_y_, [&](int tile) {
    const int tx = tile % tiles_x_, ty = tile / tiles_x_, x0 = tx * kSplatTileSize;
    const size_t begin = tile_begin_[tile];
    const TileSplat<T>* splats = tile_splats_.data() + begin;
    // Every strip of the tile at once, back to front: each splat's gradient is summed over the tile in lanes, then
    // kept for the tile's entry (summed over the splat's tiles below, in their order). Strip s is row s / kStrips,
    // pixels from x0 + kLanes (s % kStrips).
    const int y0 = ty * kSplatTileSize, rows = std::min(kSplatTileSize, height - y0);
    const int strips = std::min(kStrips, (width - x0 + kLanes - 1) / kLanes);
    std::array<RowBackward<T>, kSplatTileSize * kStrips> strip;
    std::array<uint32_t, kSplatTileSize * kStrips> strip_most{};
    for (int r = 0; r < rows; ++r) {
      for (int k = 0; k < strips; ++k) {
        RowBackward<T>& row = strip[r * kStrips + k];
        const int xs = x0 + k * kLanes, lanes = std::min(kLanes, width - xs);
        for (int l = 0; l < kLanes; ++l) {
          const size_t pixel = static_cast<size_t>(y0 + r) * width + xs + std::min(l, lanes - 1);
          const T* g = &d_rgb[3 * pixel];
          const uint32_t count = l < lanes ? contributors_[pixel] : 0;
          row.count[l] = static_cast<Lane<T>>(count);
          row.transmittance[l] = row.final_transmittance[l] = transmittance_[pixel];
          row.g_red[l] = g[0], row.g_green[l] = g[1], row.g_blue[l] = g[2];
          row.background_dot[l] = background[0] * g[0] + background[1] * g[1] + background[2] * g[2];
          strip_most[r * kStrips + k] = std::max(strip_most[r * kStrips + k], count);
        }
      }
    }
    const uint32_t most = *std::max_element(strip_most.begin(), strip_most.end());
    std::array<T, kStrips> strip_x;  // the strips' first pixel centres
    std::array<V<T>, kStrips> px;
    for (int k = 0; k < kStrips; ++k) {
      strip_x[k] = T(x0 + k * kLanes) + T(0.5);
      px[k] = strip_x[k] + lanes::Iota<T>();
    }
    for (size_t e = most; e-- > 0;) {
      LaneGradient<T> gradient;
      int first, end;
      BoxRows(splats[e], y0, rows, &first, &end);
      for (int r = first; r < end; ++r) {
        for (int k = 0; k < strips; ++k) {
          const int i = r * kStrips + k;
          const T py = T(y0 + r) + T(0.5);
          if (e < strip_most[i] && splats[e].Reaches(strip_x[k], strip_x[k] + T(kLanes - 1), py)) {
            BackwardSplat(splats[e].s, e, px[k], py, &strip[i], &gradient);
          }
        }
      }
      entry_grads_[begin + e] = gradient.Sum();
    }
    std::fill(entry_grads_.begin() + begin + most, entry_grads_.begin() + tile_begin_[tile + 1], Splat2D<T>{});
  });
  ListEntriesBySplat();
  if (screen_grads) screen_grads->resize(2 * n, T(0));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) {
      if (rects_[i].Empty()) continue;
      // Its tiles' gradients in the order of the tiles: the same sum whatever thread took which tile.
      Splat2D<T> sum;
      for (size_t k = slot_begin_[i]; k < slot_begin_[i + 1]; ++k) {
        const Splat2D<T>& b = entry_grads_[slots_[k]];
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
