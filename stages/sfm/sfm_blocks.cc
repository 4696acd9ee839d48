#include "stages/sfm/sfm_blocks.h"

#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "base/errors.h"
#include "base/file_util.h"
#include "base/format.h"
#include "formats/colmap_database.h"
#include "stages/sfm/feature_matching.h"

namespace p2n {
namespace fs = std::filesystem;
namespace {

// Where block b of `count` blocks of `size` items begins (block b: [BlockBegin(b), BlockBegin(b + 1))): sizes
// differ by one at most.
size_t BlockBegin(size_t size, size_t count, size_t b) { return size * b / count; }

// The pairs listed in `list` ("i j" lines).
std::vector<std::pair<size_t, size_t>> ReadPairs(const fs::path& list) {
  std::istringstream lines(ReadTextFile(list));
  std::vector<std::pair<size_t, size_t>> pairs;
  size_t i = 0, j = 0;
  while (lines >> i >> j) pairs.emplace_back(i, j);
  if (!lines.eof()) throw InternalError(format("'{}' is not a list of pairs of photos", list.string()));
  return pairs;
}

}  // namespace

std::vector<ExtractionBlock> PlanExtractionBlocks(const std::vector<CameraGroup>& groups, size_t block_images) {
  std::vector<ExtractionBlock> blocks;
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::vector<std::string>& images = groups[g].images;
    const size_t count = (images.size() + block_images - 1) / block_images;
    for (size_t b = 0; b < count; ++b) {
      blocks.push_back({g, std::vector<std::string>(images.begin() + BlockBegin(images.size(), count, b),
                                                    images.begin() + BlockBegin(images.size(), count, b + 1))});
    }
  }
  return blocks;
}

fs::path ExtractionBlockList(const fs::path& dir, int part) { return dir / std::to_string(part) / "images.txt"; }

fs::path ExtractionBlockDatabase(const fs::path& dir, int part) { return dir / std::to_string(part) / "database.db"; }

std::vector<int> WriteExtractionBlocks(const std::vector<ExtractionBlock>& blocks, const fs::path& dir) {
  std::vector<int> parts;
  for (size_t k = 0; k < blocks.size(); ++k) {
    const int part = static_cast<int>(k) + 1;
    fs::create_directories(ExtractionBlockList(dir, part).parent_path());
    std::string lines;
    for (const std::string& name : blocks[k].images) lines += name + "\n";
    WriteFileAtomic(ExtractionBlockList(dir, part), lines);
    parts.push_back(part);
  }
  return parts;
}

void MergeExtractionBlocks(const std::vector<ExtractionBlock>& blocks, const fs::path& dir, const fs::path& database,
                           bool shared_camera) {
  fs::rename(ExtractionBlockDatabase(dir, 1), database);
  ColmapDatabase merged(database);
  std::map<size_t, uint32_t> cameras;  // a group's shared camera
  cameras[blocks.front().group] = 1;   // the first camera of a new database
  for (size_t k = 1; k < blocks.size(); ++k) {
    const auto shared = cameras.find(blocks[k].group);
    const std::optional<uint32_t> camera =
        shared_camera && shared != cameras.end() ? std::optional<uint32_t>(shared->second) : std::nullopt;
    const uint32_t first = merged.AppendImages(ExtractionBlockDatabase(dir, static_cast<int>(k) + 1), camera);
    cameras.emplace(blocks[k].group, first);
  }
}

void RemoveBlockDatabase(const fs::path& path) {
  fs::remove(path);
  fs::remove(path.string() + "-journal");
}

fs::path MatchingBlockPairs(const fs::path& dir, int part) { return dir / std::to_string(part) / "pairs.txt"; }

fs::path MatchingBlockDatabase(const fs::path& dir, int part) { return dir / std::to_string(part) / "matches.db"; }

fs::path MatchingBlockNames(const fs::path& dir, int part) { return dir / std::to_string(part) / "names.txt"; }

std::vector<int> WriteMatchingBlocks(const std::vector<std::pair<size_t, size_t>>& pairs, size_t count,
                                     const fs::path& dir) {
  std::vector<int> parts;
  for (size_t b = 0; b < count; ++b) {
    const int part = static_cast<int>(b) + 1;
    std::string lines;
    for (size_t p = BlockBegin(pairs.size(), count, b); p < BlockBegin(pairs.size(), count, b + 1); ++p) {
      lines += format("{} {}\n", pairs[p].first, pairs[p].second);
    }
    fs::create_directories(MatchingBlockPairs(dir, part).parent_path());
    WriteFileAtomic(MatchingBlockPairs(dir, part), lines);
    parts.push_back(part);
  }
  return parts;
}

void MatchBlock(const fs::path& database, const fs::path& dir, int part) {
  const std::vector<std::pair<size_t, size_t>> pairs = ReadPairs(MatchingBlockPairs(dir, part));
  const std::vector<ColmapDatabaseImage> images = ColmapDatabase(database, /*read_only=*/true).Images();
  std::set<uint32_t> seen;
  for (const auto& [a, b] : pairs) {
    for (const size_t k : {a, b}) {
      if (k < images.size()) seen.insert(images[k].id);
    }
  }
  const fs::path matches = MatchingBlockDatabase(dir, part);
  RemoveBlockDatabase(matches);
  ColmapDatabase::CreateBlock(database, matches, {seen.begin(), seen.end()});
  MatchIntoDatabase(database, pairs, matches);
  // The pairs matched here (none the stage's database already held), each once.
  const ColmapDatabase block(matches, /*read_only=*/true);
  std::set<uint64_t> listed;
  std::string names;
  for (const auto& [a, b] : pairs) {
    if (a < images.size() && b < images.size() && block.HasMatches(images[a].id, images[b].id) &&
        listed.insert(ColmapPairId(images[a].id, images[b].id)).second) {
      names += format("{} {}\n", images[a].id, images[b].id);  // the block database's names (CreateBlock)
    }
  }
  WriteFileAtomic(MatchingBlockNames(dir, part), names);
}

void MergeMatchingBlocks(const fs::path& dir, const std::vector<int>& parts, const fs::path& database) {
  ColmapDatabase merged(database);
  for (const int part : parts) merged.AppendMatches(MatchingBlockDatabase(dir, part));
}

}  // namespace p2n
