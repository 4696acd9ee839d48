#pragma once
// The tile-based rasterizer of 3D Gaussian Splatting on the CPU, and its backward pass in closed form.
// Forward: project every Gaussian (projection.h), list it in each 16x16 tile where it can be blended (under its
// 3-sigma square and the box of the ellipse where its alpha reaches 1/255), sort each tile's list by depth, and
// blend front to back per pixel: alpha = min(0.99, opacity · exp(-½ dᵀ Σ₂⁻¹ d)), skipping alpha < 1/255 and
// stopping before the transmittance falls below 1e-4; the background fills what remains. Backward: each pixel
// walks its list again back to front from its last contributor, recovering the transmittance by division. Both
// take a strip of a tile's row at a time, passing over the splats whose box misses it, and read the tile's splats
// from one copy in list order (the forward makes it, 56 bytes an entry in float, and Backward reuses it). Tiles are
// TBB tasks.

#include <array>
#include <vector>

#include "base/camera.h"
#include "splat/gaussians.h"
#include "splat/projection.h"

namespace p2n {

inline constexpr int kSplatTileSize = 16;

// A splat in a tile's list: it and the box outside which it is blended nowhere.
template <typename T>
struct TileSplat {
  Splat2D<T> s;
  std::array<T, 4> box;  // x0, x1, y0, y1 (pixels)

  // Whether it can be blended at a pixel of the strip whose pixel centres run from (x, y) to (x_last, y).
  bool Reaches(T x, T x_last, T y) const { return y >= box[2] && y <= box[3] && x_last >= box[0] && x <= box[1]; }
};

struct RasterOptions {
  ProjectionOptions projection;
  std::array<double, 3> background = {0, 0, 0};
};

template <typename T>
class Rasterizer {
 public:
  // Renders `gaussians` seen by `camera`. Backward() uses what it keeps: `gaussians` must stay unchanged and
  // alive until then.
  void Forward(const Gaussians<T>& gaussians, const PinholeCamera& camera, const RasterOptions& options);

  int width() const { return camera_.width; }
  int height() const { return camera_.height; }
  // RGB per pixel, row-major, 3 values each.
  const std::vector<T>& rgb() const { return rgb_; }
  // What the Gaussians leave of the background per pixel (1 - the pixel's opacity).
  const std::vector<T>& transmittance() const { return transmittance_; }
  // Σ weight · depth along the view axis per pixel (divided by 1 - transmittance: the expected depth).
  const std::vector<T>& weighted_depth() const { return depth_; }
  // Gaussians drawn (in front of the near plane, finite), and tile-list entries.
  size_t drawn() const { return drawn_; }
  size_t tile_entries() const { return entries_.size(); }
  bool IsDrawn(size_t i) const { return !rects_[i].Empty(); }

  // Adds to `grads` (shaped like the Gaussians) the gradient of a loss whose gradient with respect to rgb() is
  // `d_rgb`. With `screen_grads`, adds to it the gradient with respect to each Gaussian's 2D mean (2 per
  // Gaussian, pixels), which densification reads. The same sums whatever the number of threads; one call at a time
  // (it keeps buffers between calls).
  void Backward(const std::vector<T>& d_rgb, Gaussians<T>* grads, std::vector<T>* screen_grads = nullptr) const;

 private:
  struct Rect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // tiles [x0, x1) x [y0, y1); empty when not drawn
    bool Empty() const { return x0 >= x1 || y0 >= y1; }
  };
  void Project();
  Rect TileRect(const Splat2D<T>& s, T half_x, T half_y) const;
  void BinAndSort();
  void Blend();
  void ListEntriesBySplat() const;

  const Gaussians<T>* gaussians_ = nullptr;
  RasterOptions options_;
  SplatCamera<T> camera_;
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<Splat2D<T>> splats_;
  std::vector<Rect> rects_;              // the tiles under each Gaussian's 3-sigma square (drawn: any)
  std::vector<Rect> blended_;            // within those, the tiles where it can be blended: those it is listed in
  std::vector<std::array<T, 4>> boxes_;  // x0, x1, y0, y1: the box (pixels) outside which it is not blended
  size_t drawn_ = 0;
  std::vector<size_t> tile_begin_;         // tiles_x · tiles_y + 1 offsets into entries_
  std::vector<uint32_t> entries_;          // Gaussian indices, each tile's sorted front to back
  std::vector<TileSplat<T>> tile_splats_;  // entries_' splats and boxes, copied for the blend and Backward
  std::vector<T> rgb_, transmittance_, depth_;
  std::vector<uint32_t> contributors_;  // per pixel: entries of its tile up to and including its last blended
  // Backward's, kept between calls for their memory: each tile entry's gradient, and the entries by splat
  // (ListEntriesBySplat).
  mutable std::vector<Splat2D<T>> entry_grads_;
  mutable std::vector<size_t> slot_begin_;
  mutable std::vector<uint32_t> slots_;
};

extern template class Rasterizer<float>;
extern template class Rasterizer<double>;

}  // namespace p2n
