#include "nerf/renderer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include "base/declared_fields.h"
#include "nerf/denormals.h"
#include "nerf/ray_march.h"
#include "nerf/volume_rendering.h"

namespace p2n {
namespace {

constexpr size_t kChunkRays = 256;
constexpr int kTileSide = 16;  // kTileSide^2 = kChunkRays: a chunk is one tile

}  // namespace

std::vector<MarchSample> SampleRay(const NerfModel& model, const Ray& ray, double near, double far, double step,
                                   size_t max_samples, std::mt19937_64* jitter) {
  std::vector<MarchSample> samples;
  RayMarch(model, ray, near, far, step, jitter).Next(max_samples, &samples);
  return samples;
}

double DefaultStepScale(const NerfModel& model) { return model.space == SceneSpace::kBounded ? 0.5 : 1.0; }

double StepScale(const NerfModel& model, const RenderOptions& options) {
  return options.step_scale > 0 ? options.step_scale : DefaultStepScale(model);
}

double SamplingDistance(const NerfModel& model, const Ray& ray, double t) {
  switch (model.space) {
    case SceneSpace::kBounded:
      return t;
    case SceneSpace::kUnbounded:
      return t <= 2 ? t : 2 + 2 * std::log(0.5 * t);
    case SceneSpace::kForward: {
      const ForwardRay forward = ToForward(model.forward, ray);
      return forward.valid ? forward.NdcDistance(t) : t;
    }
  }
  return t;
}

void RenderOptions::Check() const {
  CheckField(*this, step_scale, step_scale >= 0 && std::isfinite(step_scale), "must be at least 0");
  CheckField(*this, min_transmittance, min_transmittance >= 0 && min_transmittance < 1, "must be in [0, 1)");
  CheckField(*this, max_samples, max_samples >= 1, "must be at least 1");
}

void RenderRays(const NerfModel& model, const std::vector<Ray>& rays, const std::vector<Eigen::Vector2d>& near_far,
                const RenderOptions& options, float* rgb, float* depth, float* opacity, RenderStats* stats) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  const double step = model.march_step * StepScale(model, options);
  std::atomic<size_t> marched{0}, evaluated{0};
  tbb::parallel_for(size_t{0}, (rays.size() + kChunkRays - 1) / kChunkRays, [&](size_t chunk) {
    FlushDenormalsOnThisThread();
    const size_t first = chunk * kChunkRays, count = std::min(rays.size(), first + kChunkRays) - first;
    // Each ray is marched only as far as its rounds need: the steps beyond where it turns opaque are never taken.
    std::vector<RayMarch> marches;
    marches.reserve(count);
    for (size_t r = 0; r < count; ++r) {
      const Eigen::Vector2d& range = near_far[first + r];
      marches.emplace_back(model, rays[first + r], range[0], range[1], step, nullptr);
    }
    std::vector<std::vector<MarchSample>> samples(count);
    std::vector<CompositeAccumulator<float>> accumulators(count);
    std::vector<size_t> next(count, 0);
    size_t chunk_marched = 0, chunk_evaluated = 0;
    Eigen::MatrixXf positions, directions, density, colour;
    std::vector<std::pair<size_t, size_t>> round;  // (ray, sample)
    for (size_t width = 8;; width = std::min<size_t>(width * 2, 128)) {
      round.clear();
      for (size_t r = 0; r < count; ++r) {
        if (accumulators[r].Done(options.min_transmittance)) continue;
        const size_t wanted = std::min(next[r] + width, options.max_samples);
        if (samples[r].size() < wanted) chunk_marched += marches[r].Next(wanted - samples[r].size(), &samples[r]);
        for (size_t k = next[r]; k < std::min(samples[r].size(), wanted); ++k) round.emplace_back(r, k);
      }
      if (round.empty()) break;
      positions.resize(3, round.size());
      directions.resize(3, round.size());
      for (size_t i = 0; i < round.size(); ++i) {
        const Ray& ray = rays[first + round[i].first];
        positions.col(i) =
            FieldPoint(model, ray.origin + samples[round[i].first][round[i].second].t * ray.direction).cast<float>();
        directions.col(i) = ray.direction.cast<float>();
      }
      model.field->Render(positions, directions, &density, &colour);
      for (size_t i = 0; i < round.size(); ++i) {
        const auto [r, k] = round[i];
        next[r] = k + 1;
        if (accumulators[r].Done(options.min_transmittance)) continue;
        const MarchSample& s = samples[r][k];
        accumulators[r].Add(density(0, i), colour.col(i).data(), static_cast<float>(s.t), static_cast<float>(s.delta));
        ++chunk_evaluated;
      }
    }
    for (size_t r = 0; r < count; ++r) {
      const CompositeResult<float> result = accumulators[r].Finish(model.background.data());
      std::copy(result.rgb, result.rgb + 3, rgb + 3 * (first + r));
      // RenderView divides by the opacity: the median depth is passed as if it were an expected one.
      depth[first + r] = options.median_depth ? std::max(result.median_depth, 0.0f) * result.opacity : result.depth;
      opacity[first + r] = result.opacity;
    }
    marched += chunk_marched;
    evaluated += chunk_evaluated;
    if (options.on_rays_done) options.on_rays_done(count);
  });
  if (stats != nullptr) {
    stats->rays += rays.size();
    stats->samples_marched += marched;
    stats->samples_evaluated += evaluated;
    stats->seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
}

RenderedView RenderView(const NerfModel& model, const PinholeCamera& camera, double near, double far,
                        const RenderOptions& options) {
  const size_t pixels = static_cast<size_t>(camera.width) * camera.height;
  // Rays in tile order; order[i] is the pixel of ray i.
  std::vector<Ray> rays;
  std::vector<size_t> order;
  rays.reserve(pixels);
  order.reserve(pixels);
  for (int tile_y = 0; tile_y < camera.height; tile_y += kTileSide) {
    for (int tile_x = 0; tile_x < camera.width; tile_x += kTileSide) {
      for (int y = tile_y; y < std::min(camera.height, tile_y + kTileSide); ++y) {
        for (int x = tile_x; x < std::min(camera.width, tile_x + kTileSide); ++x) {
          rays.push_back(CameraRay(camera, x + 0.5, y + 0.5));
          order.push_back(size_t(y) * camera.width + x);
        }
      }
    }
  }
  const std::vector<Eigen::Vector2d> near_far(pixels, Eigen::Vector2d(near, far));
  std::vector<float> rgb(3 * pixels), depth(pixels), opacity(pixels);
  RenderedView view;
  for (FloatImage* image : {&view.rgb, &view.depth, &view.opacity}) {
    image->width = camera.width;
    image->height = camera.height;
    image->channels = image == &view.rgb ? 3 : 1;
    image->pixels.assign(pixels * image->channels, 0.0f);
  }
  RenderRays(model, rays, near_far, options, rgb.data(), depth.data(), opacity.data(), &view.stats);
  for (size_t i = 0; i < pixels; ++i) {
    const size_t p = order[i];
    std::copy(&rgb[3 * i], &rgb[3 * i + 3], &view.rgb.pixels[3 * p]);
    view.opacity.pixels[p] = opacity[i];
    view.depth.pixels[p] = opacity[i] > 1e-6f ? depth[i] / opacity[i] : 0.0f;
  }
  return view;
}

}  // namespace p2n
