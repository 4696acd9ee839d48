#pragma once
// Rendering a trained model: rays are marched through the occupancy grid (no samples in empty space) and
// their samples evaluated in rounds that grow (8, 16, 32, ... per ray), dropping rays whose transmittance has
// fallen below the threshold, so occluded space costs nothing either. Chunks of rays run in parallel.

#include <Eigen/Core>

#include <random>
#include <vector>

#include "nerf/camera.h"
#include "nerf/float_image.h"
#include "nerf/nerf_model.h"

namespace p2n {

struct RenderOptions {
  double step_scale = 1;          // sample spacing = the model's march step x this
  float min_transmittance = 1e-4f;  // rays stop below it (0: never)
  size_t max_samples = 4096;      // per ray
};

struct RenderStats {
  size_t rays = 0;
  size_t samples_marched = 0;    // in occupied space
  size_t samples_evaluated = 0;  // before early termination
  double seconds = 0;
};

// Samples of `field_ray` within [near, far] (field units) inside the unit cube: stratified (the model's
// stratified_samples bins), or every `step` through occupied cells. With `jitter`, sample positions are random
// within their bin or step (training); without, they are in the middle.
std::vector<MarchSample> SampleFieldRay(const NerfModel& model, const Ray& field_ray, double near, double far,
                                        double step, size_t max_samples, std::mt19937_64* jitter);

// Renders world rays (unit directions) between their near and far distances (world units; near < 0 or
// far <= near: the whole box). Writes rgb (3 per ray), depth (world units, weighted by opacity) and opacity.
void RenderRays(const NerfModel& model, const std::vector<Ray>& rays, const std::vector<Eigen::Vector2d>& near_far,
                const RenderOptions& options, float* rgb, float* depth, float* opacity, RenderStats* stats);

struct RenderedView {
  FloatImage rgb, depth, opacity;  // depth: expected distance along the ray / opacity (0 where nothing)
  RenderStats stats;
};

RenderedView RenderView(const NerfModel& model, const PinholeCamera& camera, double near, double far,
                        const RenderOptions& options);

}  // namespace p2n
