#pragma once
// Rendering a trained model: rays are marched through the occupancy grid (no samples in empty space) and
// their samples evaluated in rounds that grow (8, 16, 32, ... per ray), dropping rays whose transmittance has
// fallen below the threshold, so occluded space costs nothing either. Chunks of rays run in parallel.

#include <Eigen/Core>

#include <functional>
#include <random>
#include <vector>

#include "base/camera.h"
#include "base/float_image.h"
#include "nerf/nerf_model.h"

namespace p2n {

struct RenderOptions {
  static constexpr const char* kName = "render";  // checks name render.FIELD
  // Sample spacing = the model's march step x this; 0: DefaultStepScale(model).
  double step_scale = 0;
  // Rays stop below it (0: never). 1e-3 leaves out at most a quarter of an 8-bit level of colour, for 5-6% less
  // time than 1e-4 at the same PSNR (docs/benchmarks.md, rendering).
  // Training and its evaluations keep the trainer's (TrainerOptions::min_transmittance).
  float min_transmittance = 1e-3f;
  size_t max_samples = 4096;  // per ray
  // Depth images hold the median depth (where the opacity first reaches one half; robust to haze in front of a
  // surface and to the mix at its edges) instead of the expected one.
  bool median_depth = false;
  // Called (from any worker thread) with the number of rays just finished; e.g. to advance a progress bar.
  std::function<void(size_t)> on_rays_done;

  template <class V>
  void Visit(V& v) {
    v("step_scale", step_scale);
    v("min_transmittance", min_transmittance);
    v("max_samples", max_samples);
    v("median_depth", median_depth);
  }
  // std::invalid_argument naming the field and its rule (RenderRays checks its options).
  void Check() const;
};

struct RenderStats {
  size_t rays = 0;
  size_t samples_marched = 0;    // in occupied space, as far as each ray was followed
  size_t samples_evaluated = 0;  // before early termination
  double seconds = 0;
};

// Samples of the world `ray` within [near, far] (none when far <= near; negative: the whole scene), distances in world
// units: stratified (the model's stratified_samples bins over the scene box), or every `step` through occupied
// cells; in an unbounded scene the step grows with the distance beyond the unit box (step * t / 2), so that
// contracted space is sampled about evenly; in a forward-facing one the samples are even in NDC (from near, or
// the near plane, to infinity: `far` does not apply) and their lengths (delta) are in NDC units, as the densities
// there are. With `jitter`, samples are shifted by a random fraction of a step (training); without, they sit in
// the middle of their segments. At most `max_samples`, the first of the march (ray_march.h takes it in pieces).
std::vector<MarchSample> SampleRay(const NerfModel& model, const Ray& ray, double near, double far, double step,
                                   size_t max_samples, std::mt19937_64* jitter);

// The render step (as a multiple of the model's march step) when none is given. Training samples at the march
// step with random offsets. In a bounded scene (sharp surfaces) a render with fixed offsets at half of it is
// closer to the photos for about twice the samples; in an unbounded one (real captures) it gains nothing, so the
// render samples at the training step there (docs/benchmarks.md, rendering).
double DefaultStepScale(const NerfModel& model);
// The step RenderRays takes with `options`, as a multiple of the model's march step: options.step_scale, or
// DefaultStepScale where it is 0.
double StepScale(const NerfModel& model, const RenderOptions& options);

// Distance along a ray (from its origin, world units) in the metric in which SampleRay's step is the same
// everywhere, so that a length in it is a number of samples: the world distance in a bounded scene; in an
// unbounded one t up to 2 and 2 + 2 ln(t / 2) beyond, where the step grows as t / 2; in a forward-facing one the
// NDC distance from where the ray crosses the near plane.
double SamplingDistance(const NerfModel& model, const Ray& ray, double t);

// Renders world rays (unit directions) between their near and far distances (world units; negative: the whole
// scene). Writes rgb (3 per ray), depth (world units, weighted by opacity; the median depth times the opacity
// with options.median_depth, 0 where the opacity never reaches a half) and opacity.
void RenderRays(const NerfModel& model, const std::vector<Ray>& rays, const std::vector<Eigen::Vector2d>& near_far,
                const RenderOptions& options, float* rgb, float* depth, float* opacity, RenderStats* stats);

struct RenderedView {
  FloatImage rgb, depth, opacity;  // depth: expected distance along the ray / opacity (0 where nothing)
  RenderStats stats;
};

// Renders every pixel of `camera` in tiles of 16 x 16 pixels (nearby rays meet the same grid cells and hash
// entries), the tiles in parallel.
RenderedView RenderView(const NerfModel& model, const PinholeCamera& camera, double near, double far,
                        const RenderOptions& options);

}  // namespace p2n
