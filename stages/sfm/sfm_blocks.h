#pragma once
// The sfm stage's work in blocks that a scheduler runs as jobs of their own (the stage's parts), each block's files
// in a folder of its own, merged by the stage's job:
// - feature extraction in blocks of photos: the stage's job cuts each camera group's photos into blocks and writes
//   each one's photo list; each part runs COLMAP's feature_extractor on its list into a database of its own; the
//   stage's job merges the blocks' databases, in order, into the one a single extraction writes (the same images,
//   cameras and keypoints; COLMAP's descriptors differ in a few bytes between any two of its runs);
// - our descriptor matching in blocks of pairs: each part matches its pairs of the stage's database (read only) into
//   a database of its own, which COLMAP's geometric verification of them then reads and writes; the stage's job
//   appends their matches and verified geometries to its database, where COLMAP finds every pair done.

#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "stages/sfm/sfm_options.h"

namespace p2n {

// The photos by the camera that took them, as the sfm stage solves them: one group per camera their EXIF names
// (make, model, lens, focal length; a video's frames: the video) and image size; photos without EXIF by size
// alone. With sfm.single_camera each group shares one COLMAP camera.
struct CameraGroup {
  std::string label;                // "Apple, iPhone 12, 4.2 mm, 4032x3024", or "4032x3024" without EXIF
  std::vector<std::string> images;  // names in images/
};

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

// Removes what a stopped run left of a block's database at `path` (SQLite's journal too).
void RemoveBlockDatabase(const std::filesystem::path& path);

// The blocks' databases in `dir` merged in order into `database` (block 1's moved there, the others appended);
// with `shared_camera` (sfm.single_camera) the blocks of a group share the camera of its first block.
void MergeExtractionBlocks(const std::vector<ExtractionBlock>& blocks, const std::filesystem::path& dir,
                           const std::filesystem::path& database, bool shared_camera);

// The kind of the sfm stage's parts that match descriptors.
inline constexpr const char* kMatchingWork = "matching";

// `pairs` (indices of the photos in name order) cut into `count` blocks of consecutive pairs, as even as can be,
// block k's written to MatchingBlockPairs(dir, k), k from 1; returns the blocks' numbers.
std::vector<int> WriteMatchingBlocks(const std::vector<std::pair<size_t, size_t>>& pairs, size_t count,
                                     const std::filesystem::path& dir);
// Block `part`'s pairs ("i j" lines), the database of its matches, and the list of them by name for COLMAP.
std::filesystem::path MatchingBlockPairs(const std::filesystem::path& dir, int part);
std::filesystem::path MatchingBlockDatabase(const std::filesystem::path& dir, int part);
std::filesystem::path MatchingBlockNames(const std::filesystem::path& dir, int part);

// Block `part`'s pairs of `database`'s photos matched (MatchIntoDatabase) into the block's own database, made with
// what COLMAP needs to verify them (ColmapDatabase::CreateBlock); writes MatchingBlockNames, the pairs it matched
// by the block database's names, the ids ("5 7" lines: COLMAP's matches_importer verifies them there).
void MatchBlock(const std::filesystem::path& database, const std::filesystem::path& dir, int part);
// The matches and verified geometries of the blocks `parts` appended to `database`.
void MergeMatchingBlocks(const std::filesystem::path& dir, const std::vector<int>& parts,
                         const std::filesystem::path& database);

}  // namespace p2n
