#include "stages/extraction_blocks.h"

#include <map>
#include <optional>

#include "base/file_util.h"
#include "formats/colmap_database.h"

namespace p2n {
namespace fs = std::filesystem;

std::vector<ExtractionBlock> PlanExtractionBlocks(const std::vector<CameraGroup>& groups, size_t block_images) {
  std::vector<ExtractionBlock> blocks;
  for (size_t g = 0; g < groups.size(); ++g) {
    const std::vector<std::string>& images = groups[g].images;
    const size_t count = (images.size() + block_images - 1) / block_images;
    for (size_t b = 0; b < count; ++b) {
      // Block b takes [n b / count, n (b + 1) / count): sizes differ by one at most.
      const auto begin = images.begin() + images.size() * b / count,
                 end = images.begin() + images.size() * (b + 1) / count;
      blocks.push_back({g, std::vector<std::string>(begin, end)});
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

}  // namespace p2n
