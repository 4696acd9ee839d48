#pragma once
// A trained radiance field that renders without its training data: the field, its occupancy grid, the
// background it was trained against, and the sample spacing; stored in model.bin (magic, format version, a
// JSON header with the configs, then the parameters).
//
// Rays, distances, densities and the sample spacing are in world units (transforms.json's normalised frame);
// the field sees points of its unit cube. A bounded scene maps the box [-1, 1]^3 linearly onto it. An
// unbounded one is first contracted (nerfacto's L-infinity form): points inside [-1, 1]^3 stay, a point x
// outside goes to (2 - 1/|x|) x/|x| (|.| the max norm), so all of space fits in [-2, 2]^3, which maps onto the
// unit cube. A forward-facing one holds the normalised device coordinates of a reference camera
// (forward_space.h), [-1, 1]^3 mapped onto the unit cube; its densities are per NDC unit.

#include <array>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "base/binary_io.h"
#include "nerf/forward_space.h"
#include "nerf/occupancy_grid.h"
#include "nerf/radiance_field.h"
#include "nerf/rays.h"

namespace p2n {

// 2: the occupancy grid's densities only where the header says so (checkpoints; model.bin keeps the bits alone).
inline constexpr uint32_t kModelFormatVersion = 2;

// How the scene's space maps onto the field's unit cube (above).
enum class SceneSpace { kBounded, kUnbounded, kForward };
const char* SceneSpaceName(SceneSpace space);  // "bounded", "unbounded", "forward"
// std::invalid_argument for another name.
SceneSpace SceneSpaceFromName(const std::string& name);

struct NerfModel {
  std::unique_ptr<RadianceField<float>> field;
  OccupancyGrid occupancy{1};                // one occupied cell until the trainer or a model file sets the real one
  std::array<float, 3> background{1, 1, 1};  // behind the scene when rendering (the training background)
  SceneSpace space = SceneSpace::kBounded;
  ForwardFrame forward;                            // kForward's reference camera
  double march_step = 0;                           // sample spacing along a ray (unbounded: near the centre)
  int stratified_samples = 0;                      // > 0: samples per ray in equal bins instead (no occupancy grid)
  nlohmann::json info = nlohmann::json::object();  // kept with the model: normalisation, training summary
};

// Where a world point of an unbounded scene lies in the field's unit cube. Inline, as FieldPoint(): ray marching
// asks this at every step.
inline Eigen::Vector3d UnboundedFieldPoint(const Eigen::Vector3d& world) {
  const double norm = world.cwiseAbs().maxCoeff();
  if (norm <= 1) return 0.25 * world + Eigen::Vector3d::Constant(0.5);
  const double inverse = 1 / norm;
  return (0.25 * (2 - inverse) * inverse) * world + Eigen::Vector3d::Constant(0.5);
}

// Where a world point lies in the field's unit cube.
inline Eigen::Vector3d FieldPoint(const NerfModel& model, const Eigen::Vector3d& world) {
  if (model.space == SceneSpace::kBounded) return 0.5 * (world + Eigen::Vector3d::Ones());
  if (model.space == SceneSpace::kForward) return 0.5 * (ForwardNdc(model.forward, world) + Eigen::Vector3d::Ones());
  return UnboundedFieldPoint(world);
}
// d(FieldPoint)/d(world) at `world`.
Eigen::Matrix3d FieldPointJacobian(const NerfModel& model, const Eigen::Vector3d& world);

// With `occupancy_densities`, the occupancy grid's densities too: what a resumed training needs, and most of a
// model's bytes at 256^3 (67 MB); a render, an export or the splats need the grid's bits alone.
void WriteModel(const NerfModel& model, BinaryWriter* writer, bool occupancy_densities);
// Reads what WriteModel wrote; std::runtime_error naming the source when it is damaged, of a newer format, or
// its config is invalid.
NerfModel ReadModel(BinaryReader* reader);

// model.bin (without the occupancy densities): written to a temporary file, flushed to disk and renamed into place.
void SaveModel(const NerfModel& model, const std::filesystem::path& path);
NerfModel LoadModel(const std::filesystem::path& path);

// The whole file (std::runtime_error naming it when it cannot be opened).
std::vector<char> ReadBinaryFile(const std::filesystem::path& path);

}  // namespace p2n
