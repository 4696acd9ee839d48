#pragma once
// A trained radiance field that renders without its training data: the field, its occupancy grid, the
// background it was trained against, and the sample spacing; stored in model.bin (magic, format version, a
// JSON header with the configs, then the parameters). The field lives in the unit cube: the normalised scene's
// box [-1, 1]^3 (transforms.json's frame) maps to [0, 1]^3, so field lengths are half of world lengths.

#include <array>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "nerf/binary_io.h"
#include "nerf/occupancy_grid.h"
#include "nerf/radiance_field.h"
#include "nerf/rays.h"

namespace p2n {

inline constexpr uint32_t kModelFormatVersion = 1;
inline constexpr double kFieldFromWorldScale = 0.5;

// The ray in field coordinates (same direction; distances scale by kFieldFromWorldScale).
inline Ray FieldRayFromWorld(const Ray& world) {
  return {(world.origin + Eigen::Vector3d::Ones()) * kFieldFromWorldScale, world.direction};
}

struct NerfModel {
  std::unique_ptr<RadianceField<float>> field;
  OccupancyGrid occupancy{128};
  std::array<float, 3> background{1, 1, 1};  // behind the scene when rendering (the training background)
  double march_step = 0;                      // sample spacing in field units along a ray
  int stratified_samples = 0;                 // > 0: samples per ray in equal bins instead (no occupancy grid)
  nlohmann::json info = nlohmann::json::object();  // kept with the model: normalisation, training summary
};

void WriteModel(const NerfModel& model, BinaryWriter* writer);
// Reads what WriteModel wrote; std::runtime_error naming the source when it is damaged, of a newer format, or
// its config is invalid.
NerfModel ReadModel(BinaryReader* reader);

// model.bin: written to a temporary file, flushed to disk and renamed into place.
void SaveModel(const NerfModel& model, const std::filesystem::path& path);
NerfModel LoadModel(const std::filesystem::path& path);

// Helpers for files in this format: the whole file, and an atomic durable write.
std::vector<char> ReadBinaryFile(const std::filesystem::path& path);
void WriteBinaryFileAtomic(const std::filesystem::path& path, const std::vector<char>& bytes);

}  // namespace p2n
