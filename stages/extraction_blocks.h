#pragma once
// Feature extraction in blocks of photos that a scheduler runs as jobs of their own (the sfm stage's parts): the
// stage's job cuts each camera group's photos into blocks and writes each one's photo list; each part runs COLMAP's
// feature_extractor on its list into a database of its own; the stage's job merges the blocks' databases, in order,
// into the one a single extraction would have written (the same images, ids, cameras and features).

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "stages/sfm_stage.h"

namespace p2n {

// The kind of the sfm stage's parts that extract features (StageContext::RunParts).
inline constexpr const char* kExtractionWork = "extraction";

struct ExtractionBlock {
  size_t group = 0;                 // index of its camera group
  std::vector<std::string> images;  // names, in the group's order
};

// Each group's photos, in order, cut into as few blocks of at most `block_images` as can be, as even as can be.
std::vector<ExtractionBlock> PlanExtractionBlocks(const std::vector<CameraGroup>& groups, size_t block_images);

// Writes block k's photo list to ExtractionBlockList(dir, k), k from 1; returns the blocks' numbers.
std::vector<int> WriteExtractionBlocks(const std::vector<ExtractionBlock>& blocks, const std::filesystem::path& dir);

// Block `part`'s photo list (COLMAP's --image_list_path), and the database its extraction writes.
std::filesystem::path ExtractionBlockList(const std::filesystem::path& dir, int part);
std::filesystem::path ExtractionBlockDatabase(const std::filesystem::path& dir, int part);

// The blocks' databases in `dir` merged in order into `database` (block 1's moved there, the others appended);
// with `shared_camera` (sfm.single_camera) the blocks of a group share the camera of its first block.
void MergeExtractionBlocks(const std::vector<ExtractionBlock>& blocks, const std::filesystem::path& dir,
                           const std::filesystem::path& database, bool shared_camera);

}  // namespace p2n
