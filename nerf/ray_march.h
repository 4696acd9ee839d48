#pragma once
// The samples of one world ray through a model's scene (docs/design.md §6): stratified bins over the scene box
// (vanilla), or every `step` through the occupancy grid's occupied cells, the step growing with the distance
// beyond the unit box in an unbounded scene, even in NDC in a forward-facing one. A march can be taken in
// pieces (the renderer takes a ray's next few samples only while the ray is still visible): the pieces together
// are the samples of one march to the end.

#include <random>
#include <vector>

#include "nerf/forward_space.h"
#include "nerf/nerf_model.h"
#include "nerf/occupancy_grid.h"
#include "nerf/rays.h"

namespace p2n {

class RayMarch {
 public:
  // The march of the world `ray` (unit direction) within [near, far] (world units; negative: the whole scene;
  // nothing when far <= near), as SampleRay (renderer.h) describes. With `jitter`, the samples are shifted by a
  // random fraction of a step (training); without, they sit in the middle of their segments.
  RayMarch(const NerfModel& model, const Ray& ray, double near, double far, double step, std::mt19937_64* jitter);

  // Appends the next samples, at most `count` (fewer only where the ray ends), to `out`; returns how many.
  size_t Next(size_t count, std::vector<MarchSample>* out);

 private:
  enum class Kind { kNothing, kStratified, kUnbounded, kBounded, kForward };

  // The cube marches (bounded, forward): the ray in the field's cube, or nothing where it misses the box.
  void StartInCube(const Ray& cube_ray, double begin, double end, double offset, std::mt19937_64* jitter);
  size_t NextUnbounded(size_t count, std::vector<MarchSample>* out);
  size_t NextInCube(size_t count, std::vector<MarchSample>* out);

  const NerfModel* model_;
  Kind kind_ = Kind::kNothing;
  Ray ray_;                              // the world ray (unbounded), or the ray in the field's cube
  double position_ = 0, end_ = 0;        // where the next segment starts, and the march's end, along ray_
  double step_ = 0;                      // along ray_ (a cube's half of the world step)
  ForwardRay forward_;                   // forward: the world ray's NDC segment
  double forward_length_ = 0;            // its length in the field's cube
  std::vector<MarchSample> stratified_;  // every sample of a stratified march, world units
  size_t taken_ = 0;                     // of them
};

}  // namespace p2n
